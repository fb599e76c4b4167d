/* sd-lighting world background, vertex shader: one triangle that covers the screen, at the far
 * plane (z = w), so that with the depth test LESS_EQUAL it shows only where nothing was drawn. */
void main()
{
  sd_ndc = pos;
  gl_Position = vec4(pos, 1.0, 1.0);
}
