/* Colour decoding (include/clayfit/image.h): the sRGB transfer curve of
 * IEC 61966-2-1:1999 and the stored-value-to-radiance map of one image.
 *
 *   linear  = encoded / 12.92                        encoded <= 0.04045
 *           = ((encoded + 0.055) / 1.055)^2.4         otherwise
 *   encoded = 12.92 linear                            linear <= 0.0031308
 *           = 1.055 linear^(1/2.4) − 0.055            otherwise
 *
 * The standard's two thresholds do not quite meet (the pieces differ by
 * about 3e-8 there), so a round trip through the curve is exact to
 * rounding everywhere except within about 1e-7 of the thresholds. Negative
 * values are mapped by odd symmetry. */
#include <math.h>

#include "clayfit/image.h"

double cf_srgb_to_linear(double encoded) {
  if (encoded < 0.0) return -cf_srgb_to_linear(-encoded);
  if (encoded <= 0.04045) return encoded / 12.92;
  return pow((encoded + 0.055) / 1.055, 2.4);
}

double cf_linear_to_srgb(double linear) {
  if (linear < 0.0) return -cf_linear_to_srgb(-linear);
  if (linear <= 0.0031308) return 12.92 * linear;
  return 1.055 * pow(linear, 1.0 / 2.4) - 0.055;
}

/* transfer⁻¹: stored value to linear. */
static double to_linear(const cf_decode *decode, double stored) {
  switch (decode->transfer) {
    case CF_TRANSFER_SRGB:
      return cf_srgb_to_linear(stored);
    case CF_TRANSFER_GAMMA:
      return stored < 0.0 ? -pow(-stored, decode->gamma) : pow(stored, decode->gamma);
    case CF_TRANSFER_LINEAR:
      break;
  }
  return stored;
}

unsigned cf_decode_pixel(const cf_decode *decode, const float *stored, int channels,
                         double radiance[3]) {
  const int grey = channels < 3;
  unsigned clipped = 0;
  for (int c = 0; c < 3; ++c) {
    const double value = stored[grey ? 0 : c];
    if (value >= decode->clip_level) clipped |= 1u << c;
    radiance[c] = (to_linear(decode, value) - decode->black_level) / decode->exposure;
  }
  return clipped;
}
