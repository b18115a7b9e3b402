/* A cube face's capture into its slot of the cube atlas (engine/frame/features/cubes.py): its
 * colour, and its view depth (the capture's normal target's w) in a target of its own. The
 * viewport is the slot; ``origin`` its corner. */
void main()
{
  ivec2 p = ivec2(gl_FragCoord.xy) - origin;
  out_color = texelFetch(src_color, p, 0);
  out_depth = texelFetch(src_normal, p, 0).w;
}
