#include "bake/embree_scene.h"

#include "util/number_string.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace sd {
namespace {

std::string vec_string(const glm::dvec3& v) {
  return "(" + number_string(v.x) + ", " + number_string(v.y) + ", " + number_string(v.z) + ")";
}

bool finite(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

}  // namespace

void check_points(const char* name, const std::vector<glm::dvec3>& points) {
  constexpr double kFloatMax = static_cast<double>(std::numeric_limits<float>::max());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const glm::dvec3& p = points[i];
    if (!finite(p)) {
      throw std::invalid_argument(std::string(name) + "[" + std::to_string(i) + "] contains NaN or infinity");
    }
    if (std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}) > 1e-3 * kFloatMax) {
      throw std::invalid_argument(std::string(name) + "[" + std::to_string(i) + "] = " + vec_string(p) +
                                  " is beyond the float32 range Embree works in");
    }
  }
}

void check_triangles(const char* name, const std::vector<Triangle>& triangles, std::size_t vertex_count,
                     const char* vertices_name) {
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const std::int64_t index = triangles[t][k];
      if (index < 0 || static_cast<std::uint64_t>(index) >= vertex_count) {
        throw std::invalid_argument(std::string(name) + "[" + std::to_string(t) + "][" + std::to_string(k) +
                                    "] = " + std::to_string(index) + " is out of range for " +
                                    std::to_string(vertex_count) + " " + vertices_name);
      }
    }
  }
}

namespace {

// n / |n|, scaled by its largest component first (no overflow or underflow); zero for a zero or
// non-finite n.
glm::dvec3 unit_or_zero(const glm::dvec3& n) {
  const double scale = std::max({std::abs(n.x), std::abs(n.y), std::abs(n.z)});
  if (!finite(n) || !(scale > 0.0) || !std::isfinite(scale)) return glm::dvec3(0.0);
  return glm::normalize(n / scale);
}

}  // namespace

std::vector<glm::dvec3> unit_normals(const std::vector<glm::dvec3>& normals, const std::vector<glm::dvec3>& vertices,
                                     const std::vector<Triangle>& triangles, std::vector<std::int64_t>* fallback) {
  std::vector<glm::dvec3> out(normals.size());
  bool repairs = false;
  for (std::size_t i = 0; i < normals.size(); ++i) {
    out[i] = unit_or_zero(normals[i]);
    repairs = repairs || out[i] == glm::dvec3(0.0);
  }
  if (!repairs) return out;
  std::vector<glm::dvec3> faces(normals.size(), glm::dvec3(0.0));  // Σ of the faces' cross products
  for (const Triangle& t : triangles) {
    const glm::dvec3 &a = vertices[t[0]], &b = vertices[t[1]], &c = vertices[t[2]];
    const glm::dvec3 area_normal = glm::cross(b - a, c - a);
    for (int k = 0; k < 3; ++k) faces[t[k]] += area_normal;
  }
  for (std::size_t i = 0; i < normals.size(); ++i) {
    if (out[i] != glm::dvec3(0.0)) continue;
    out[i] = unit_or_zero(faces[i]);
    if (out[i] == glm::dvec3(0.0)) out[i] = glm::dvec3(0.0, 0.0, 1.0);
    if (fallback) fallback->push_back(static_cast<std::int64_t>(i));
  }
  return out;
}

EmbreeScene::EmbreeScene() {
  device_ = rtcNewDevice(nullptr);
  if (!device_) throw std::runtime_error("Embree: cannot create a device (" + error_name(rtcGetDeviceError(nullptr)) + ")");
  rtcSetDeviceErrorFunction(device_, &EmbreeScene::on_error, this);
  // first_hit needs every hit on both sides: an Embree built without filter functions or with
  // back-face culling would let every ray-origin candidate pass unseen.
  if (rtcGetDeviceProperty(device_, RTC_DEVICE_PROPERTY_FILTER_FUNCTION_SUPPORTED) == 0 ||
      rtcGetDeviceProperty(device_, RTC_DEVICE_PROPERTY_BACKFACE_CULLING_ENABLED) != 0) {
    rtcReleaseDevice(device_);
    throw std::runtime_error("Embree: this build lacks filter functions or culls back faces; the bake needs both sides");
  }
  scene_ = rtcNewScene(device_);
  check("rtcNewScene");
  rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
}

EmbreeScene::~EmbreeScene() {
  if (scene_) rtcReleaseScene(scene_);
  if (device_) rtcReleaseDevice(device_);
}

int EmbreeScene::add(const std::vector<glm::dvec3>& vertices, const std::vector<Triangle>& triangles) {
  if (triangles.empty()) return -1;
  RTCGeometry geometry = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
  check("rtcNewGeometry");
  auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                         3 * sizeof(float), vertices.size()));
  auto* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                            3 * sizeof(unsigned), triangles.size()));
  if (!vb || !ib) {
    rtcReleaseGeometry(geometry);
    check("rtcSetNewGeometryBuffer");
    throw std::runtime_error("Embree: cannot allocate geometry buffers");
  }
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    vb[3 * i + 0] = static_cast<float>(vertices[i].x);
    vb[3 * i + 1] = static_cast<float>(vertices[i].y);
    vb[3 * i + 2] = static_cast<float>(vertices[i].z);
  }
  std::vector<glm::vec3> normals(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) ib[3 * t + k] = static_cast<unsigned>(triangles[t][k]);
    const glm::dvec3& a = vertices[triangles[t][0]];
    normals[t] = glm::vec3(glm::cross(vertices[triangles[t][1]] - a, vertices[triangles[t][2]] - a));
  }
  // Only rtcIntersect1 (first_hit) calls it: the bake's occlusion rays run without a filter.
  rtcSetGeometryIntersectFilterFunction(geometry, &EmbreeScene::probe_filter);
  rtcSetGeometryBuildQuality(geometry, RTC_BUILD_QUALITY_HIGH);
  rtcCommitGeometry(geometry);
  const unsigned id = rtcAttachGeometry(scene_, geometry);
  rtcReleaseGeometry(geometry);
  check("building the geometry");
  if (face_normals_.size() <= id) face_normals_.resize(id + 1);
  face_normals_[id] = std::move(normals);
  if (orientation_.size() <= id) orientation_.resize(id + 1);
  return static_cast<int>(id);
}

void EmbreeScene::orient(int geometry, std::vector<std::int8_t> orientation) {
  if (geometry >= 0) orientation_.at(static_cast<std::size_t>(geometry)) = std::move(orientation);
}

void EmbreeScene::commit() {
  rtcCommitScene(scene_);
  check("rtcCommitScene");
}

void trace_occlusion(RTCScene scene, RTCRay* rays, unsigned count) {
#if SD_EMBREE_MAJOR >= 4
  for (unsigned i = 0; i < count; ++i) rtcOccluded1(scene, &rays[i]);
#else
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  if (count == 1) {
    rtcOccluded1(scene, &context, rays);
  } else {
    rtcOccluded1M(scene, &context, rays, count, sizeof(RTCRay));
  }
#endif
}

bool EmbreeScene::occluded(const glm::dvec3& origin, const glm::dvec3& dir) const {
  RTCRay ray = occlusion_ray(origin, dir);
  trace_occlusion(scene_, &ray, 1);
  return is_occluded(ray);
}

namespace {

// rtcIntersect1's context, extended with the probe's state (Embree passes the pointer through to
// the filter: Embree 3's intersect context, Embree 4's ray query context).
#if SD_EMBREE_MAJOR >= 4
using QueryContext = RTCRayQueryContext;
#else
using QueryContext = RTCIntersectContext;
#endif
struct ProbeContext {
  QueryContext context;
  const std::vector<std::vector<glm::vec3>>* face_normals;
  const std::vector<std::vector<std::int8_t>>* orientation;
  int skipped_geometry;
  const std::vector<unsigned>* skipped;
  float tolerance;
  float first_t;
  EmbreeScene::Side first_side;
};

}  // namespace

void EmbreeScene::probe_filter(const RTCFilterFunctionNArguments* args) {
  auto* probe = reinterpret_cast<ProbeContext*>(args->context);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] == 0) continue;
    args->valid[i] = 0;  // every hit is rejected, so traversal reports every triangle on the segment
    const unsigned geometry = RTCHitN_geomID(args->hit, args->N, i);
    const unsigned primitive = RTCHitN_primID(args->hit, args->N, i);
    if (static_cast<int>(geometry) == probe->skipped_geometry &&
        std::find(probe->skipped->begin(), probe->skipped->end(), primitive) != probe->skipped->end()) {
      continue;
    }
    const glm::vec3 dir(RTCRayN_dir_x(args->ray, args->N, i), RTCRayN_dir_y(args->ray, args->N, i),
                        RTCRayN_dir_z(args->ray, args->N, i));
    const float t = RTCRayN_tfar(args->ray, args->N, i);  // the candidate hit's distance
    const std::vector<std::int8_t>& orientation = (*probe->orientation)[geometry];
    const int sign = orientation.empty() ? 1 : orientation[primitive];
    const float facing = glm::dot((*probe->face_normals)[geometry][primitive], dir);
    if (facing == 0.0f) continue;  // the segment runs in the triangle's plane
    const Side side = sign == 0 ? Side::kSheet : (facing * static_cast<float>(sign) > 0.0f ? Side::kBack : Side::kFront);
    if (probe->first_side == Side::kNothing || t < probe->first_t - probe->tolerance) {
      probe->first_t = t;
      probe->first_side = side;
    } else if (t <= probe->first_t + probe->tolerance && side != Side::kFront && probe->first_side != Side::kBack) {
      probe->first_side = side;  // at one t a back outranks a sheet, a sheet a front
    }
  }
}

EmbreeScene::Hit EmbreeScene::first_hit(const glm::dvec3& origin, const glm::dvec3& dir, double t_max,
                                        int skipped_geometry, const std::vector<unsigned>& skipped,
                                        double tolerance) const {
  ProbeContext probe;
#if SD_EMBREE_MAJOR >= 4
  rtcInitRayQueryContext(&probe.context);
#else
  rtcInitIntersectContext(&probe.context);
#endif
  probe.face_normals = &face_normals_;
  probe.orientation = &orientation_;
  probe.skipped_geometry = skipped_geometry;
  probe.skipped = &skipped;
  probe.tolerance = static_cast<float>(tolerance >= 0.0 ? tolerance : 1e-4 * t_max);
  probe.first_t = 0.0f;
  probe.first_side = Side::kNothing;
  RTCRayHit query{};
  query.ray = occlusion_ray(origin, dir);
  query.ray.tfar = static_cast<float>(t_max);
  query.hit.geomID = RTC_INVALID_GEOMETRY_ID;
#if SD_EMBREE_MAJOR >= 4
  RTCIntersectArguments arguments;
  rtcInitIntersectArguments(&arguments);
  arguments.context = &probe.context;
  rtcIntersect1(scene_, &query, &arguments);
#else
  rtcIntersect1(scene_, &probe.context, &query);
#endif
  return {probe.first_side, static_cast<double>(probe.first_t)};
}

std::string EmbreeScene::error_name(RTCError code) {
  switch (code) {
    case RTC_ERROR_NONE: return "no error";
    case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
    case RTC_ERROR_CANCELLED: return "cancelled";
    default: return "unknown error";
  }
}

void EmbreeScene::on_error(void* self, RTCError code, const char* message) {
  auto* scene = static_cast<EmbreeScene*>(self);
  if (scene->error_.empty()) scene->error_ = error_name(code) + (message ? std::string(": ") + message : "");
}

void EmbreeScene::check(const char* what) {
  const RTCError code = rtcGetDeviceError(device_);
  if (code != RTC_ERROR_NONE || !error_.empty()) {
    throw std::runtime_error(std::string("Embree failed in ") + what + ": " + (error_.empty() ? error_name(code) : error_));
  }
}

}  // namespace sd
