void main()
{
  gl_Position = light_view_proj * model * vec4(pos, 1.0);
}
