/* The cheapest full-screen pass: the baseline the post benchmark divides by. */
void main()
{
  out_color = post_mix(post_source());
}
