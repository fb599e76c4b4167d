/* The scene's triangles as a ray BVH (SD_REFLECTION_RAYS; sdnative.ray_bvh, live/ray_bvh.py): the
 * RGBA32F texture sd_ray_bvh, laid out as the data texture (sd_data_texel), holds node i in texels
 * 2i (its box's lower corner, a) and 2i + 1 (upper corner, b), then from texel sd.ray_bvh.x (2 x
 * the node count) triangle j in three texels (p0, p1 - p0, p2 - p0). An inner node's children are
 * nodes a and b; a leaf has a = -1 - its first triangle and b triangles. World space, relative to
 * the casters' centre (float32 world positions far from the origin would round the rays away);
 * sd.ray_bvh.yzw is the drawn object's origin there. The walk is sdnative.ray_bvh_occluded's,
 * which the tests compare with every triangle's test. */
#ifdef SD_REFLECTION_RAYS
vec4 sd_ray_bvh_texel(int index)
{
  return texelFetch(sd_ray_bvh, ivec2(index & ((1 << SD_TEXTURE_WIDTH_LOG2) - 1), index >> SD_TEXTURE_WIDTH_LOG2), 0);
}

/* Whether the ray origin + t dir, t > t_min (origin relative to sd.ray_bvh.yzw), hits a triangle. */
bool sd_ray_occluded(vec3 origin, vec3 dir, float t_min)
{
  if (sd.ray_bvh.x < 1.0) {
    return false;
  }
  const float tiny = 1e-20;
  vec3 inverse = 1.0 / vec3(abs(dir.x) > tiny ? dir.x : (dir.x < 0.0 ? -tiny : tiny),
                            abs(dir.y) > tiny ? dir.y : (dir.y < 0.0 ? -tiny : tiny),
                            abs(dir.z) > tiny ? dir.z : (dir.z < 0.0 ? -tiny : tiny));
  int first_triangle = int(sd.ray_bvh.x + 0.5);
  int stack[SD_RAY_BVH_MAX_DEPTH + 1];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    int node = stack[--top];
    vec4 lower = sd_ray_bvh_texel(2 * node);
    vec4 upper = sd_ray_bvh_texel(2 * node + 1);
    vec3 t0 = (lower.xyz - origin) * inverse;
    vec3 t1 = (upper.xyz - origin) * inverse;
    vec3 near_t = min(t0, t1);
    vec3 far_t = max(t0, t1);
    float enter = max(max(near_t.x, near_t.y), max(near_t.z, t_min));
    float leave = min(min(far_t.x, far_t.y), far_t.z);
    if (enter > leave) {
      continue;
    }
    if (lower.w < 0.0) {
      int first = first_triangle + 3 * int(-1.0 - lower.w + 0.5);
      int count = int(upper.w + 0.5);
      for (int k = 0; k < count; k++) {
        vec3 p0 = sd_ray_bvh_texel(first + 3 * k).xyz;
        vec3 e1 = sd_ray_bvh_texel(first + 3 * k + 1).xyz;
        vec3 e2 = sd_ray_bvh_texel(first + 3 * k + 2).xyz;
        vec3 p = cross(dir, e2);
        float det = dot(e1, p);
        if (det == 0.0) {
          continue;
        }
        float inv_det = 1.0 / det;
        vec3 s = origin - p0;
        float u = dot(s, p) * inv_det;
        vec3 q = cross(s, e1);
        float v = dot(dir, q) * inv_det;
        if (u >= 0.0 && u <= 1.0 && v >= 0.0 && u + v <= 1.0 && dot(e2, q) * inv_det > t_min) {
          return true;
        }
      }
    }
    else if (top + 2 <= SD_RAY_BVH_MAX_DEPTH + 1) {   /* always, in a tree the builder made */
      stack[top++] = int(upper.w + 0.5);
      stack[top++] = int(lower.w + 0.5);
    }
  }
  return false;
}
#endif
