/* Colour decoding: the sRGB curve of IEC 61966-2-1 (known values, round
 * trips, monotonicity, the piecewise threshold) and cf_decode_pixel (clip
 * mask per channel, black level, exposure, gamma, grey pixels). */
#include <math.h>
#include <stdio.h>

#include "clayfit/image.h"
#include "support/check.h"

CHECK_MAIN_STATE;

/* Within about 1e-7 of the standard's thresholds the two pieces of the
 * curve do not meet, so round trips there are exact only to ~3e-8. */
static int near_linear_threshold(double linear) {
  return fabs(linear - 0.0031308) < 2e-8;
}
static int near_encoded_threshold(double encoded) {
  return fabs(encoded - 0.04045) < 2e-7;
}

static void test_srgb(void) {
  /* known values: the ends, the middle grey, 8-bit 188 ~ 0.5 linear */
  CHECK(cf_srgb_to_linear(0.0) == 0.0, "0 -> %g", cf_srgb_to_linear(0.0));
  CHECK(fabs(cf_srgb_to_linear(1.0) - 1.0) < 1e-15, "1 -> %.17g", cf_srgb_to_linear(1.0));
  CHECK(fabs(cf_linear_to_srgb(1.0) - 1.0) < 1e-15, "1 -> %.17g", cf_linear_to_srgb(1.0));
  double mid = cf_srgb_to_linear(0.5);
  printf("srgb 0.5 -> linear %.12f; linear 0.18 -> srgb %.12f; 188/255 -> %.12f\n", mid,
         cf_linear_to_srgb(0.18), cf_srgb_to_linear(188.0 / 255.0));
  CHECK(fabs(mid - 0.214041140482232) < 1e-12, "srgb 0.5 -> %.15f", mid);
  CHECK(fabs(cf_linear_to_srgb(0.18) - 0.461356129500442) < 1e-12, "linear 0.18 -> %.15f",
        cf_linear_to_srgb(0.18));
  CHECK(fabs(cf_srgb_to_linear(0.04) - 0.04 / 12.92) < 1e-18, "linear segment");
  CHECK(fabs(cf_linear_to_srgb(0.002) - 0.002 * 12.92) < 1e-18, "linear segment");
  /* the threshold: 0.04045 is still on the linear piece, just above it the power */
  CHECK(cf_srgb_to_linear(0.04045) == 0.04045 / 12.92, "0.04045 on the linear piece");
  double above = 0.04045 + 1e-9;
  CHECK(cf_srgb_to_linear(above) == pow((above + 0.055) / 1.055, 2.4), "power piece above");
  CHECK(cf_linear_to_srgb(0.0031308) == 12.92 * 0.0031308, "0.0031308 on the linear piece");
  double jump = fabs(12.92 * 0.0031308 - (1.055 * pow(0.0031308, 1 / 2.4) - 0.055));
  printf("the pieces differ by %.3g at the threshold\n", jump);
  CHECK(jump < 5e-8, "discontinuity %g", jump);
  /* negative values: odd symmetry */
  CHECK(cf_srgb_to_linear(-0.5) == -cf_srgb_to_linear(0.5), "odd symmetry");
  CHECK(cf_linear_to_srgb(-0.01) == -cf_linear_to_srgb(0.01), "odd symmetry");

  /* round trips and monotonicity over [0, 1] */
  const int n = 1000000;
  double worst_linear = 0.0, worst_encoded = 0.0, worst_near = 0.0;
  int monotone = 1;
  double previous_l = -1.0, previous_e = -1.0;
  for (int i = 0; i <= n; ++i) {
    double x = (double)i / n;
    double l = cf_srgb_to_linear(x), e = cf_linear_to_srgb(x);
    if (!(l > previous_l) || !(e > previous_e)) monotone = 0;
    previous_l = l;
    previous_e = e;
    double back_l = fabs(cf_srgb_to_linear(e) - x); /* linear -> srgb -> linear */
    double back_e = fabs(cf_linear_to_srgb(l) - x); /* srgb -> linear -> srgb */
    if (near_linear_threshold(x)) {
      if (back_l > worst_near) worst_near = back_l;
    } else if (back_l > worst_linear) {
      worst_linear = back_l;
    }
    if (near_encoded_threshold(x)) {
      if (back_e > worst_near) worst_near = back_e;
    } else if (back_e > worst_encoded) {
      worst_encoded = back_e;
    }
  }
  /* the threshold windows themselves, densely */
  for (int i = -1000; i <= 1000; ++i) {
    double l = 0.0031308 + i * 1e-11, e = 0.04045 + i * 1e-10;
    double a = fabs(cf_srgb_to_linear(cf_linear_to_srgb(l)) - l);
    double b = fabs(cf_linear_to_srgb(cf_srgb_to_linear(e)) - e);
    if (a > worst_near) worst_near = a;
    if (b > worst_near) worst_near = b;
  }
  printf(
      "round trips over [0, 1] (%d steps): linear->srgb->linear %.3g, srgb->linear->srgb %.3g; "
      "within 2e-7 of the thresholds %.3g\n",
      n, worst_linear, worst_encoded, worst_near);
  CHECK(monotone, "both curves strictly increasing over [0, 1]");
  CHECK(worst_linear < 1e-12, "linear round trip %g", worst_linear);
  CHECK(worst_encoded < 1e-12, "srgb round trip %g", worst_encoded);
  CHECK(worst_near < 5e-8, "round trip near the thresholds %g", worst_near);
}

static void test_decode(void) {
  double r[3];
  /* linear, black level and exposure */
  cf_decode linear = {CF_TRANSFER_LINEAR, 1.0, 0.01, INFINITY, 2.0};
  float stored[3] = {0.21f, 0.41f, 0.01f};
  unsigned mask = cf_decode_pixel(&linear, stored, 3, r);
  printf("linear (black 0.01, exposure 2): %.9g %.9g %.9g, mask %u\n", r[0], r[1], r[2], mask);
  CHECK(mask == 0, "never clipped with clip_level = inf: %u", mask);
  for (int c = 0; c < 3; ++c)
    CHECK(fabs(r[c] - ((double)stored[c] - 0.01) / 2.0) < 1e-15, "channel %d: %.17g", c, r[c]);
  CHECK(fabs(r[2]) < 1e-9, "black level gives zero: %g", r[2]);
  float below[3] = {0.005f, 0.0f, 0.01f};
  cf_decode_pixel(&linear, below, 3, r);
  CHECK(r[0] < 0.0 && r[1] < 0.0, "not clamped below the black level: %g %g", r[0], r[1]);

  /* clip mask: tested per channel on the stored value, before decoding */
  cf_decode clip = {CF_TRANSFER_SRGB, 1.0, 0.0, 0.98, 1.0};
  float hot[3] = {0.99f, 0.5f, 0.98f};
  mask = cf_decode_pixel(&clip, hot, 3, r);
  printf("srgb, clip 0.98: mask %u for %g %g %g\n", mask, hot[0], hot[1], hot[2]);
  CHECK(mask == (1u | 4u), "mask %u, expected 5 (red and blue at or above 0.98)", mask);
  CHECK(fabs(r[1] - cf_srgb_to_linear(0.5)) < 1e-15, "green decoded: %g", r[1]);
  /* a clipped channel is decoded at the clip level, all it says (docs/model.md (38)) */
  double level = cf_srgb_to_linear(0.98);
  CHECK(fabs(r[0] - level) < 1e-15 && fabs(r[2] - level) < 1e-15,
        "a clipped channel is decoded at the clip level: %g %g", r[0], r[2]);
  /* the clip test is on the stored value, not on the radiance */
  cf_decode clip_linear = {CF_TRANSFER_SRGB, 1.0, 0.0, 0.9, 0.01};
  float dim[3] = {0.5f, 0.5f, 0.5f};
  mask = cf_decode_pixel(&clip_linear, dim, 3, r);
  CHECK(mask == 0 && r[0] > 0.9, "radiance %g above the clip level but stored 0.5: mask %u", r[0],
        mask);

  /* gamma */
  cf_decode gamma = {CF_TRANSFER_GAMMA, 2.2, 0.0, INFINITY, 1.0};
  float g[3] = {0.5f, 0.25f, 1.0f};
  cf_decode_pixel(&gamma, g, 3, r);
  printf("gamma 2.2: %.12f %.12f %.12f\n", r[0], r[1], r[2]);
  for (int c = 0; c < 3; ++c)
    CHECK(fabs(r[c] - pow((double)g[c], 2.2)) < 1e-15, "gamma channel %d: %g", c, r[c]);
  float negative = -0.25f;
  cf_decode_pixel(&gamma, &negative, 1, r);
  CHECK(isfinite(r[0]) && r[0] == -pow(0.25, 2.2), "negative stored value: %g", r[0]);

  /* grey: one channel read as r = g = b; two channels (grey + alpha) too */
  float grey = 0.6f;
  mask = cf_decode_pixel(&clip, &grey, 1, r);
  CHECK(mask == 0 && r[0] == r[1] && r[1] == r[2] && r[0] == cf_srgb_to_linear((double)0.6f),
        "grey %g %g %g, mask %u", r[0], r[1], r[2], mask);
  float white = 1.0f;
  mask = cf_decode_pixel(&clip, &white, 1, r);
  CHECK(mask == 7u, "a clipped grey pixel clips all three channels: mask %u", mask);
  float grey_alpha[2] = {0.3f, 1.0f};
  mask = cf_decode_pixel(&clip, grey_alpha, 2, r);
  CHECK(mask == 0 && r[0] == r[2] && r[0] == cf_srgb_to_linear((double)0.3f),
        "grey + alpha: %g %g %g, mask %u (alpha is not a colour)", r[0], r[1], r[2], mask);
  /* four channels: alpha ignored */
  float rgba[4] = {0.1f, 0.2f, 0.3f, 1.0f};
  mask = cf_decode_pixel(&clip, rgba, 4, r);
  CHECK(mask == 0 && r[2] == cf_srgb_to_linear((double)0.3f), "rgba: mask %u", mask);
}

int main(void) {
  test_srgb();
  test_decode();
  return check_finish("test_colour");
}
