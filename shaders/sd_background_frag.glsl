/* sd-lighting world background, fragment shader (prepended by sd_equirect.glsl, SD_EQUIRECT_MAP
 * = sd_environment): the environment in the pixel's direction.
 *
 * The direction d is the pixel's ray, from two points of it unprojected by the inverse
 * view-projection (any two depths: the same for either clip-space z convention); its radiance is
 * L(g d) - g the environment rotation, as in the shading - from sd_environment (the map with its
 * strength), bilinear as Blender's Environment Texture interpolates by default, times sd_scale
 * (the exposure). */
void main()
{
  vec4 a = sd_inverse_view_projection * vec4(sd_ndc, 0.0, 1.0);
  vec4 b = sd_inverse_view_projection * vec4(sd_ndc, 0.5, 1.0);
  vec3 d = normalize(b.xyz / b.w - a.xyz / a.w);
  fragColor = vec4(sd_scale * sd_equirect(normalize(mat3(sd_to_environment) * d)), 1.0);
}
