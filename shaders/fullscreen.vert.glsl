/* One triangle covering the viewport; uv is 0..1 across the target. */
void main()
{
  uv = pos * 0.5 + 0.5;
  gl_Position = vec4(pos, 0.0, 1.0);
}
