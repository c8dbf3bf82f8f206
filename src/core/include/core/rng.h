/* A small seeded random number generator (xoshiro256**, Blackman & Vigna
 * 2018, seeded by splitmix64) for benchmarks, tests and synthetic data:
 * the same seed gives the same sequence on every machine. Header-only. */
#ifndef CLAYFIT_CORE_RNG_H
#define CLAYFIT_CORE_RNG_H

#include <math.h>
#include <stdint.h>

#include "core/vec.h"

typedef struct cf_rng {
  uint64_t s[4];
} cf_rng;

static inline uint64_t cf_rng_splitmix64(uint64_t *x) {
  uint64_t z = (*x += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

static inline cf_rng cf_rng_seed(uint64_t seed) {
  cf_rng r;
  for (int k = 0; k < 4; ++k) r.s[k] = cf_rng_splitmix64(&seed);
  return r;
}

static inline uint64_t cf_rng_next(cf_rng *r) {
  uint64_t *s = r->s;
  uint64_t x = s[1] * 5;
  uint64_t result = ((x << 7) | (x >> 57)) * 9;
  uint64_t t = s[1] << 17;
  s[2] ^= s[0];
  s[3] ^= s[1];
  s[1] ^= s[2];
  s[0] ^= s[3];
  s[2] ^= t;
  s[3] = (s[3] << 45) | (s[3] >> 19);
  return result;
}

/* Uniform in [0, 1), 53 random bits. */
static inline double cf_rng_uniform(cf_rng *r) {
  return (double)(cf_rng_next(r) >> 11) * 0x1.0p-53;
}

/* A normal deviate (Box-Muller). */
static inline double cf_rng_gaussian(cf_rng *r) {
  double u1 = cf_rng_uniform(r), u2 = cf_rng_uniform(r);
  return sqrt(-2.0 * log(1.0 - u1)) * cos(2.0 * CF_PI * u2);
}

/* Uniform in [lo, hi]. */
static inline double cf_rng_range(cf_rng *r, double lo, double hi) {
  return lo + (hi - lo) * cf_rng_uniform(r);
}

/* A uniformly distributed unit vector. */
static inline void cf_rng_unit_vector(cf_rng *r, double out[3]) {
  double z = 1.0 - 2.0 * cf_rng_uniform(r);
  double s = sqrt(fmax(0.0, 1.0 - z * z));
  double phi = 2.0 * CF_PI * cf_rng_uniform(r);
  out[0] = s * cos(phi);
  out[1] = s * sin(phi);
  out[2] = z;
}

/* A unit vector uniformly distributed on the hemisphere around unit n. */
static inline void cf_rng_hemisphere(cf_rng *r, const double n[3], double out[3]) {
  cf_rng_unit_vector(r, out);
  double d = out[0] * n[0] + out[1] * n[1] + out[2] * n[2];
  if (d < 0.0)
    for (int k = 0; k < 3; ++k) out[k] = -out[k];
}

#endif /* CLAYFIT_CORE_RNG_H */
