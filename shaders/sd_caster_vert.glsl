/* sd-lighting: what casts the bright sources' shadows, drawn into a source's shadow map
 * (live/source_shadows.py): world positions `pos` through sd_light_clip (the map's orthographic
 * view), passing on t, the distance towards the source (sd_light_t: scene/light_sources.shadow_rows'
 * row 2). */
void main()
{
  gl_Position = sd_light_clip * vec4(pos, 1.0);
  sd_t = dot(sd_light_t, vec4(pos, 1.0));
}
