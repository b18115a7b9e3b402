/* The world's ambient occlusion at half resolution (lib/gtao.glsl): the horizons of one pixel
 * of each 2x2 block (gtao_representative), marched over the full-resolution camera depth
 * prepass, packed with that pixel's view depth for the lit pass's nearest-depth upsampling. */
void main()
{
  vec2 cell = floor(gl_FragCoord.xy);
  vec2 frag = gtao_representative(cell);
  float depth = texelFetch(ao_depth, ivec2(frag), 0).r;
  if (!(depth > 0.0)) {
    out_horizons = vec4(0.0);
    return;
  }
  GtaoHorizons g = gtao_horizons(gtao_view_position(frag, depth), frag, cell);
  out_horizons = g.valid ? vec4(gtao_pack(g.h[0]), gtao_pack(g.h[1]), gtao_pack(g.h[2]), depth) :
                           vec4(-1.0, -1.0, -1.0, depth);
}
