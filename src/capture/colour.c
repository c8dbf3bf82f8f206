/* Colour decoding (include/clayfit/image.h): the sRGB transfer curve of
 * IEC 61966-2-1:1999, the camera response curves that synth renders through
 * (cf_response) and the stored-value-to-radiance map of one image.
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
#include <string.h>

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

/* ---- camera response curves (cf_response) ----
 * Each maps linear exposure in [0, 1] (1: the stated white) to a code in
 * [0, 1] and back; negative values by odd symmetry, like the sRGB curve. */

/* John Hable's "Uncharted 2" filmic curve (GDC 2010, "Uncharted 2: HDR
 * Lighting"; filmicworlds.com/blog/filmic-tonemapping-operators):
 *   f(x) = (x(Ax + CB) + DE) / (x(Ax + B) + DF) − E/F
 * with his constants; code = f(W x) / f(W), so that linear 1 maps to Hable's
 * linear white W = 11.2 and so to code 1. */
static const double hable_a = 0.15, hable_b = 0.50, hable_c = 0.10, hable_d = 0.20, hable_e = 0.02,
                    hable_f = 0.30, hable_white = 11.2;

static double hable(double x) {
  return (x * (hable_a * x + hable_c * hable_b) + hable_d * hable_e) /
             (x * (hable_a * x + hable_b) + hable_d * hable_f) -
         hable_e / hable_f;
}

static double filmic_encode(double linear) {
  if (linear < 0.0) return -filmic_encode(-linear);
  return hable(hable_white * linear) / hable(hable_white);
}

/* f(x) = y solved for x: with g = y + E/F, A(g − 1)x² + B(g − C)x + D(gF − E)
 * = 0; for 0 <= y < 1 − E/F, a < 0 <= c, so one root is >= 0:
 * x = 2c / (−b + √(b² − 4ac)) (no cancellation near 0). Codes at or above the
 * curve's asymptote (f(∞)/f(W) ≈ 1.29) have no preimage: +inf. */
static double filmic_decode(double code) {
  if (code < 0.0) return -filmic_decode(-code);
  double g = code * hable(hable_white) + hable_e / hable_f;
  if (g >= 1.0) return INFINITY;
  double a = hable_a * (g - 1.0), b = hable_b * (g - hable_c),
         c = hable_d * (g * hable_f - hable_e);
  return 2.0 * c / (-b + sqrt(b * b - 4.0 * a * c)) / hable_white;
}

static double power(double x, double exponent) {
  return x < 0.0 ? -pow(-x, exponent) : pow(x, exponent);
}

static const char *const response_names[CF_RESPONSE_COUNT] = {"linear", "srgb", "gamma2.2",
                                                              "filmic"};

const char *cf_response_name(cf_response response) {
  return (unsigned)response < CF_RESPONSE_COUNT ? response_names[response] : "?";
}

cf_status cf_response_find(const char *name, cf_response *response, cf_error *err) {
  for (int r = 0; r < CF_RESPONSE_COUNT; ++r)
    if (name && strcmp(name, response_names[r]) == 0) {
      *response = (cf_response)r;
      return CF_OK;
    }
  return cf_error_set(err, CF_EINVAL,
                      "'%s' is not a response curve (linear, srgb, gamma2.2, filmic)",
                      name ? name : "");
}

double cf_response_encode(cf_response response, double linear) {
  switch (response) {
    case CF_RESPONSE_SRGB:
      return cf_linear_to_srgb(linear);
    case CF_RESPONSE_GAMMA22:
      return power(linear, 1.0 / 2.2);
    case CF_RESPONSE_FILMIC:
      return filmic_encode(linear);
    case CF_RESPONSE_LINEAR:
    case CF_RESPONSE_COUNT:
      break;
  }
  return linear;
}

double cf_response_decode(cf_response response, double code) {
  switch (response) {
    case CF_RESPONSE_SRGB:
      return cf_srgb_to_linear(code);
    case CF_RESPONSE_GAMMA22:
      return power(code, 2.2);
    case CF_RESPONSE_FILMIC:
      return filmic_decode(code);
    case CF_RESPONSE_LINEAR:
    case CF_RESPONSE_COUNT:
      break;
  }
  return code;
}

/* transfer⁻¹: stored value to linear. */
double cf_transfer_to_linear(cf_transfer transfer, double gamma, double stored) {
  switch (transfer) {
    case CF_TRANSFER_SRGB:
      return cf_srgb_to_linear(stored);
    case CF_TRANSFER_GAMMA:
      return stored < 0.0 ? -pow(-stored, gamma) : pow(stored, gamma);
    case CF_TRANSFER_LINEAR:
      break;
  }
  return stored;
}

static double to_linear(const cf_decode *decode, double stored) {
  return cf_transfer_to_linear(decode->transfer, decode->gamma, stored);
}

/* transfer: linear to stored value, and its derivative. */
/* transfer: linear to stored value, and (slope not NULL) its derivative. */
static double from_linear(const cf_decode *decode, double linear, double *slope) {
  const double h = 1e-6; /* (the curves are smooth; central differences to ~1e-9) */
  switch (decode->transfer) {
    case CF_TRANSFER_SRGB:
      if (slope)
        *slope = (cf_linear_to_srgb(linear + h) - cf_linear_to_srgb(linear - h)) / (2.0 * h);
      return cf_linear_to_srgb(linear);
    case CF_TRANSFER_GAMMA: {
      double a = fabs(linear), stored = pow(a, 1.0 / decode->gamma);
      if (slope) *slope = a > 0.0 ? stored / (decode->gamma * a) : HUGE_VAL;
      return linear < 0.0 ? -stored : stored;
    }
    case CF_TRANSFER_LINEAR:
      break;
  }
  if (slope) *slope = 1.0;
  return linear;
}

double cf_encode_value(const cf_decode *decode, double radiance, double *slope) {
  double stored = from_linear(decode, radiance * decode->exposure + decode->black_level, slope);
  if (slope) *slope *= decode->exposure;
  return stored;
}

unsigned cf_decode_pixel(const cf_decode *decode, const float *stored, int channels,
                         double radiance[3]) {
  const int grey = channels < 3;
  unsigned clipped = 0;
  for (int c = 0; c < 3; ++c) {
    /* a clipped channel says "at least the clip level", whatever the code
     * above it (a JPEG's coding moves it): decoded at the level */
    double value = stored[grey ? 0 : c];
    if (value > decode->clip_level) value = decode->clip_level; /* (NaN stays NaN) */
    if (value >= decode->clip_level) clipped |= 1u << c;
    radiance[c] = (to_linear(decode, value) - decode->black_level) / decode->exposure;
  }
  return clipped;
}
