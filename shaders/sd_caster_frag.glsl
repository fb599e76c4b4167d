/* sd-lighting: a caster's t into the shadow map (the depth test keeps the one nearest the source). */
void main()
{
  fragColor = vec4(sd_t, 0.0, 0.0, 1.0);
}
