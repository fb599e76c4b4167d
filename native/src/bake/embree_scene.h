// Embree's occlusion scene and the checks of the meshes it is built from. Private to the library:
// the visibility bake and the reference integrator trace against the same scene.
#pragma once

#include "sdlighting/mesh.h"

// Embree 3 or 4, whichever CMake found (cmake/native_dependencies.cmake: SD_EMBREE_MAJOR). The
// differences the library meets are wrapped here and in embree_scene.cpp; the library's other
// sources reach Embree only through this header.
#if !defined(SD_EMBREE_MAJOR)
#error "SD_EMBREE_MAJOR (3 or 4) comes with the library's CMake target sdlighting"
#elif SD_EMBREE_MAJOR >= 4
#include <embree4/rtcore.h>
#else
#include <embree3/rtcore.h>
#endif

#include <glm/vec3.hpp>

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace sd {

/// Throws std::invalid_argument naming `name`[i] when a point is not finite or beyond the float32
/// range Embree works in.
void check_points(const char* name, const std::vector<glm::dvec3>& points);

/// Throws std::invalid_argument when a triangle's index is outside [0, vertex_count).
void check_triangles(const char* name, const std::vector<Triangle>& triangles, std::size_t vertex_count,
                     const char* vertices_name);

/// The normals made unit length. A zero or non-finite normal (Blender's for a vertex of degenerate
/// faces, an importer's NaN) does not fail the bake: that vertex gets the area-weighted normal of
/// its faces (the sum of their cross products), or +Z when it has no faces or they cancel, and its
/// index is appended to `fallback` (when given) so that the caller can warn. `triangles` must be
/// checked against `vertices` first.
std::vector<glm::dvec3> unit_normals(const std::vector<glm::dvec3>& normals, const std::vector<glm::dvec3>& vertices,
                                     const std::vector<Triangle>& triangles,
                                     std::vector<std::int64_t>* fallback = nullptr);

/// An occlusion ray from `origin` along `dir`, t in [0, ∞) (Embree works in float32).
inline RTCRay occlusion_ray(const glm::dvec3& origin, const glm::dvec3& dir) {
  RTCRay ray{};
  ray.org_x = static_cast<float>(origin.x);
  ray.org_y = static_cast<float>(origin.y);
  ray.org_z = static_cast<float>(origin.z);
  ray.dir_x = static_cast<float>(dir.x);
  ray.dir_y = static_cast<float>(dir.y);
  ray.dir_z = static_cast<float>(dir.z);
  ray.tnear = 0.0f;
  ray.tfar = std::numeric_limits<float>::infinity();
  ray.mask = 0xFFFFFFFFu;
  return ray;
}

/// Whether Embree marked the ray occluded (it sets tfar to −∞ on a hit).
inline bool is_occluded(const RTCRay& ray) { return ray.tfar < 0.0f; }

/// Traces `count` occlusion rays (occlusion_ray) and marks each one that is blocked (is_occluded).
/// Embree 3 takes them as one stream (rtcOccluded1M), which it packs into SIMD packets when they
/// share an origin - about twice the throughput of one call per ray on these machines
/// (visibility_benchmarks); Embree 4 dropped streams, and gets one call per ray.
void trace_occlusion(RTCScene scene, RTCRay* rays, unsigned count);

/// A committed Embree scene of the object's triangles and the occluders' (robust, high quality).
class EmbreeScene {
 public:
  EmbreeScene();
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;
  ~EmbreeScene();

  /// Adds a triangle mesh (indices already checked); returns its geometry ID, or -1 when it has no
  /// triangles (nothing is added).
  int add(const std::vector<glm::dvec3>& vertices, const std::vector<Triangle>& triangles);
  /// Builds the BVH; call once, after every add().
  void commit();
  RTCScene scene() const { return scene_; }

  /// How probes read geometry `geometry`'s triangles from now on, per triangle: +1 as wound (the
  /// default), -1 wound the other way, 0 a sheet, which has no inside (face_sides.h). Not
  /// thread-safe: call before the probes.
  void orient(int geometry, std::vector<std::int8_t> orientation);

  /// Whether the ray origin + t dir, t in [0, ∞), hits a triangle; thread-safe after commit().
  bool occluded(const glm::dvec3& origin, const glm::dvec3& dir) const;

  /// What a probe segment meets first: a triangle's front (the side its normal points to by the
  /// right-hand rule of its orientation, Blender's for +1), its back, or a sheet.
  enum class Side { kNothing, kFront, kBack, kSheet };
  struct Hit {
    Side side = Side::kNothing;
    double t = 0.0;  ///< where along the segment
  };
  /// The first triangle the segment origin + t dir, t in [0, t_max], meets. Triangles met at the
  /// same t (coplanar ones: a box standing on a floor) count as kBack when any of them is met
  /// from behind, else as kSheet when any is a sheet. Triangles `skipped` of geometry
  /// `skipped_geometry` are not seen. tolerance: how near two hits count as one t; by default
  /// 1e-4 t_max (a probe as long as the geometry it tests). Thread-safe after commit().
  Hit first_hit(const glm::dvec3& origin, const glm::dvec3& dir, double t_max, int skipped_geometry = -1,
                const std::vector<unsigned>& skipped = {}, double tolerance = -1.0) const;

 private:
  static std::string error_name(RTCError code);
  static void probe_filter(const RTCFilterFunctionNArguments* args);
  static void on_error(void* self, RTCError code, const char* message);
  void check(const char* what);

  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  std::string error_;
  std::vector<std::vector<glm::vec3>> face_normals_;  // per geometry ID, per triangle (unnormalised)
  std::vector<std::vector<std::int8_t>> orientation_;  // per geometry ID, per triangle, or empty (+1)
};

}  // namespace sd
