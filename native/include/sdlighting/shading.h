// CPU evaluators of every shading formula, for all vertices at once (both cores): the ground the
// viewport shader and the accuracy report are checked against. Equation numbers are the seed's
// (msd-notes). Each evaluator is named shade_<id> after its method id, the one name Python
// (sdnative.shade), the add-on and the GLSL (SD_METHOD_<ID>) use: unshadowed, ambient_occlusion,
// prt_diffuse, prt_matrix, prt_gaunt, msd_lobe, msd_visibility.
//
// Every evaluator computes, per vertex p and RGB channel,
//   B_p(v, g) ≈ ∫ L(g x) V_p(x) w(a_p · x) dμ(x)                                       eq. (1)
// with the lobe axis a_p = n_p for Lambert and a_p = v_n = 2(n·v)n − v for Phong, from the
// environment's coefficients *already rotated*: light[3 i + c] is coefficient i of channel c of
// x ↦ L(g x) (rotate once per frame with rotated_sh, sh_rotation.h).
#pragma once

#include "sdlighting/spherical_design.h"
#include "sdlighting/zonal_lobe.h"

#include <cstddef>
#include <cstdint>
#include <string>

namespace sd {

/// The two materials of the method.
struct Material {
  bool glossy = false;   // Phong around the mirrored view; otherwise Lambert around the normal
  double exponent = 1.0;  // Phong σ (ignored for Lambert)

  static Material lambert() { return Material{false, 1.0}; }
  static Material phong(double exponent) { return Material{true, exponent}; }
  /// "lambert" or "phong"; throws std::invalid_argument otherwise.
  static Material from_name(const std::string& name, double exponent);
  ZonalLobe lobe() const { return glossy ? ZonalLobe::phong(exponent) : ZonalLobe::lambert(); }
};

/// What every formula needs: the rotated environment, the vertices' normals and views, and the material.
struct ShadingInputs {
  int light_order = 0;             // s
  const double* light = nullptr;   // sh_count(s) × 3, coefficients of x ↦ L(g x), RGB interleaved
  size_t vertex_count = 0;
  const double* normals = nullptr;    // vertex_count × 3, unit
  const double* view_dirs = nullptr;  // vertex_count × 3, unit, vertex → eye; only read when glossy
  Material material;
};

/// Per-vertex designs of V (Theorem 2.2): vertex p owns nodes [offsets[p], offsets[p+1]).
struct VertexDesigns {
  const int64_t* offsets = nullptr;  // vertex_count + 1
  const double* nodes = nullptr;     // offsets[vertex_count] × 3
  const double* weights = nullptr;   // offsets[vertex_count]
};

/// The lobe axis a: the normal for Lambert, the mirrored view 2(n·v)n − v for Phong.
/// `normal` and `view` point to 3 doubles each.
void lobe_axis(const Material& material, const double* normal, const double* view, double* axis);

/// Unshadowed: Σ_{l<=s} ŵ_l Σ_m L_lm(g) y_lm(a) (Funk–Hecke; V = 1).
void shade_unshadowed(const ShadingInputs& in, double* out);

/// Ambient-occlusion-scaled: AO_p times the unshadowed value; ambient_occlusion[p] = Ṽ_00.
void shade_ambient_occlusion(const ShadingInputs& in, const double* ambient_occlusion, double* out);

/// Diffuse PRT, eq. (2): Σ_lm L_lm(g) (T_p)_lm with T_p = 4 V_p (n·x)_+ projected to order s
/// (transfer: vertex_count × sh_count(s)). Requires a Lambert material.
void shade_prt_diffuse(const ShadingInputs& in, const double* transfer, double* out);

/// Glossy PRT with the visibility product matrix, eqs. (8)-(9):
/// T_lm = Σ_{l'm'} M_{lm,l'm'} ŵ_l' y_l'm'(a), B = Σ_lm L_lm(g) T_lm;
/// matrices: vertex_count × sh_count(s) × sh_count(s'), row-major.
void shade_prt_matrix(const ShadingInputs& in, int visibility_order, const double* matrices, double* out);

/// Glossy PRT with Ṽ of order s' and real Gaunt coefficients, eq. (10) (the seed's (4)):
/// B = Σ_lm Σ_l'm' L_lm(g) Ṽ_l'm' Σ_l''m'' G_{lm,l'm',l''m''} ŵ_l'' y_l''m''(a);
/// visibility: vertex_count × sh_count(s').
void shade_prt_gaunt(const ShadingInputs& in, int visibility_order, const double* visibility, double* out);

/// MSD, Theorem 2.1, eq. (12): Σ_ν λ_ν L̃(g g_a x_ν) Ṽ(g_a x_ν) with a design of degree >= s+s'
/// for the lobe's weight w(x·e3) (zonal_design), g_a any rotation taking e3 to a. Equal to (10).
void shade_msd_lobe(const ShadingInputs& in, int visibility_order, const double* visibility,
                    const SphericalDesign& lobe_design, double* out);

/// MSD, Theorem 2.2, eq. (13): Σ_ν λ_Vν L̃(g x_Vν) w̃(x_Vν · a) with each vertex's design of degree
/// >= s+s' for the weight V_p and the lobe truncated at order s' (truncated_lobe). Equal to (8)-(9)
/// for the same ray samples.
void shade_msd_visibility(const ShadingInputs& in, int visibility_order, const VertexDesigns& designs,
                          double* out);

}  // namespace sd
