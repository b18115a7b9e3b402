/* One triangle covering the viewport; fragment shaders address pixels by gl_FragCoord. */
void main()
{
  gl_Position = vec4(pos, 0.0, 1.0);
}
