#include "sdlighting/shading.h"

#include "util/orthonormal_basis.h"
#include "util/parallel_for.h"
#include "sdlighting/gaunt.h"
#include "sdlighting/spherical_harmonics.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace sd {

Material Material::from_name(const std::string& name, double exponent) {
  if (name == "lambert") return lambert();
  if (name == "phong") return Material{true, ZonalLobe::phong(exponent).exponent};
  throw std::invalid_argument("unknown material '" + name + "' (expected 'lambert' or 'phong')");
}

void lobe_axis(const Material& material, const double* normal, const double* view, double* axis) {
  if (!material.glossy) {
    std::copy(normal, normal + 3, axis);
    return;
  }
  const double nv = normal[0] * view[0] + normal[1] * view[1] + normal[2] * view[2];
  for (int i = 0; i < 3; ++i) axis[i] = 2.0 * nv * normal[i] - view[i];
}

namespace {

void check_inputs(const ShadingInputs& in) {
  check_order("light order", in.light_order, kMaxShadingOrder);
  if (!in.light || (in.vertex_count > 0 && !in.normals)) throw std::invalid_argument("missing light or normals");
  if (in.material.glossy && in.vertex_count > 0 && !in.view_dirs) {
    throw std::invalid_argument("a glossy material needs view directions");
  }
  ZonalLobe::phong(in.material.exponent);  // validates the exponent
}

void check_visibility_order(int order) { check_order("visibility order", order, kMaxShadingOrder); }

// Runs shade(p, axis, rgb) for every vertex on both cores; rgb is the vertex's output triple.
template <typename Shade>
void for_each_vertex(const ShadingInputs& in, double* out, Shade&& shade) {
  parallel_for(in.vertex_count, 256, [&](size_t begin, size_t end) {
    double axis[3];
    for (size_t p = begin; p < end; ++p) {
      lobe_axis(in.material, in.normals + 3 * p, in.view_dirs ? in.view_dirs + 3 * p : nullptr, axis);
      const glm::dvec3 a = glm::normalize(glm::dvec3(axis[0], axis[1], axis[2]));
      double* rgb = out + 3 * p;
      rgb[0] = rgb[1] = rgb[2] = 0.0;
      shade(p, a, rgb);
    }
  });
}

// ŵ_l repeated over each band's 2l+1 coefficients, for l <= order.
std::vector<double> per_coefficient_factors(const ZonalLobe& lobe, int order) {
  const std::vector<double> w = lobe.coefficients(order);
  std::vector<double> out(sh_count(order));
  for (int l = 0; l <= order; ++l)
    for (int m = -l; m <= l; ++m) out[sh_index(l, m)] = w[l];
  return out;
}

// L̃(x) for the rotated environment: Σ_i light_i y_i(x), added (times `scale`) into rgb.
void add_light(const double* light, int count, const double* y, double scale, double* rgb) {
  double r = 0.0, g = 0.0, b = 0.0;
  for (int i = 0; i < count; ++i) {
    r += light[3 * i] * y[i];
    g += light[3 * i + 1] * y[i];
    b += light[3 * i + 2] * y[i];
  }
  rgb[0] += scale * r;
  rgb[1] += scale * g;
  rgb[2] += scale * b;
}

}  // namespace

void shade_unshadowed(const ShadingInputs& in, double* out) {
  check_inputs(in);
  const int k = sh_count(in.light_order);
  const std::vector<double> w = per_coefficient_factors(in.material.lobe(), in.light_order);
  for_each_vertex(in, out, [&](size_t, const glm::dvec3& a, double* rgb) {
    thread_local std::vector<double> y;
    y.resize(k);
    sh_basis(in.light_order, a, y.data());
    for (int i = 0; i < k; ++i) y[i] *= w[i];
    add_light(in.light, k, y.data(), 1.0, rgb);
  });
}

void shade_ambient_occlusion(const ShadingInputs& in, const double* ambient_occlusion, double* out) {
  shade_unshadowed(in, out);
  for (size_t p = 0; p < in.vertex_count; ++p)
    for (int c = 0; c < 3; ++c) out[3 * p + c] *= ambient_occlusion[p];
}

void shade_prt_diffuse(const ShadingInputs& in, const double* transfer, double* out) {
  check_inputs(in);
  if (in.material.glossy) throw std::invalid_argument("diffuse PRT (2) needs a Lambert material");
  const int k = sh_count(in.light_order);
  for_each_vertex(in, out, [&](size_t p, const glm::dvec3&, double* rgb) {
    add_light(in.light, k, transfer + p * k, 1.0, rgb);
  });
}

void shade_prt_matrix(const ShadingInputs& in, int visibility_order, const double* matrices, double* out) {
  check_inputs(in);
  check_visibility_order(visibility_order);
  const int k = sh_count(in.light_order), kv = sh_count(visibility_order);
  const std::vector<double> w = per_coefficient_factors(in.material.lobe(), visibility_order);
  for_each_vertex(in, out, [&](size_t p, const glm::dvec3& a, double* rgb) {
    thread_local std::vector<double> y, t;
    y.resize(kv);
    t.resize(k);
    sh_basis(visibility_order, a, y.data());
    for (int j = 0; j < kv; ++j) y[j] *= w[j];
    const double* m = matrices + p * size_t(k) * kv;
    for (int i = 0; i < k; ++i) {  // eq. (9): T_lm = Σ M_{lm,l'm'} ŵ_l' y_l'm'(v_n)
      double sum = 0.0;
      for (int j = 0; j < kv; ++j) sum += m[size_t(i) * kv + j] * y[j];
      t[i] = sum;
    }
    add_light(in.light, k, t.data(), 1.0, rgb);  // eq. (8)
  });
}

void shade_prt_gaunt(const ShadingInputs& in, int visibility_order, const double* visibility, double* out) {
  check_inputs(in);
  check_visibility_order(visibility_order);
  const int s = in.light_order, s_v = visibility_order, top = s + s_v;
  const int kv = sh_count(s_v), kt = sh_count(top);
  const std::vector<GauntEntry> gaunt = gaunt_coefficients(s, s_v, top);
  const std::vector<double> w = per_coefficient_factors(in.material.lobe(), top);
  for_each_vertex(in, out, [&](size_t p, const glm::dvec3& a, double* rgb) {
    thread_local std::vector<double> y;
    y.resize(kt);
    sh_basis(top, a, y.data());
    for (int i = 0; i < kt; ++i) y[i] *= w[i];
    const double* v = visibility + p * kv;
    for (const GauntEntry& e : gaunt) {
      const double f = v[e.b] * e.value * y[e.c];
      rgb[0] += in.light[3 * e.a] * f;
      rgb[1] += in.light[3 * e.a + 1] * f;
      rgb[2] += in.light[3 * e.a + 2] * f;
    }
  });
}

void shade_msd_lobe(const ShadingInputs& in, int visibility_order, const double* visibility,
                    const SphericalDesign& lobe_design, double* out) {
  check_inputs(in);
  check_visibility_order(visibility_order);
  if (lobe_design.degree < in.light_order + visibility_order) {
    throw std::invalid_argument("Theorem 2.1 needs a lobe design of degree >= s + s' = " +
                                std::to_string(in.light_order + visibility_order) + ", got " +
                                std::to_string(lobe_design.degree));
  }
  const int s = in.light_order, s_v = visibility_order, top = std::max(s, s_v);
  const int k = sh_count(s), kv = sh_count(s_v);
  for_each_vertex(in, out, [&](size_t p, const glm::dvec3& a, double* rgb) {
    thread_local std::vector<double> y;
    y.resize(sh_count(top));
    glm::dvec3 t1, t2;
    orthonormal_basis(a, t1, t2);
    const double* v = visibility + p * kv;
    for (int nu = 0; nu < lobe_design.size(); ++nu) {
      const glm::dvec3& x = lobe_design.nodes[nu];
      sh_basis(top, x.x * t1 + x.y * t2 + x.z * a, y.data());  // g_a x_ν
      double v_tilde = 0.0;
      for (int j = 0; j < kv; ++j) v_tilde += v[j] * y[j];
      add_light(in.light, k, y.data(), lobe_design.weights[nu] * v_tilde, rgb);
    }
  });
}

void shade_msd_visibility(const ShadingInputs& in, int visibility_order, const VertexDesigns& designs,
                          double* out) {
  check_inputs(in);
  check_visibility_order(visibility_order);
  const int s = in.light_order, k = sh_count(s);
  const std::vector<double> w = in.material.lobe().coefficients(visibility_order);
  for_each_vertex(in, out, [&](size_t p, const glm::dvec3& a, double* rgb) {
    thread_local std::vector<double> y;
    y.resize(k);
    for (int64_t nu = designs.offsets[p]; nu < designs.offsets[p + 1]; ++nu) {
      const glm::dvec3 x(designs.nodes[3 * nu], designs.nodes[3 * nu + 1], designs.nodes[3 * nu + 2]);
      sh_basis(s, x, y.data());
      const double lobe = truncated_lobe(w, visibility_order, glm::dot(x, a));
      add_light(in.light, k, y.data(), designs.weights[nu] * lobe, rgb);
    }
  });
}

}  // namespace sd
