/* Normalised light-space depth (0 near, 1 far) into a float colour target, so the lit pass can
 * compare it exactly with texelFetch. */
void main()
{
  out_depth = gl_FragCoord.z;
}
