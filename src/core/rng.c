/*
 * Seeded random streams: xoshiro256** (Blackman & Vigna 2018) seeded through
 * SplitMix64. A stream is a pure function of (seed, stream[, substream]), so a
 * realisation draws the same numbers whatever thread or process computes it.
 */
#include "karst/common.h"

#include <math.h>

static uint64_t splitmix64(uint64_t *x) {
  uint64_t z = (*x += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

/**
 * Seed the stream (seed, stream). The two words are mixed through SplitMix64
 * before filling the state, so neighbouring streams are uncorrelated.
 * Time complexity: O(1).
 */
void karst_rng_init(karst_rng_t *rng, uint64_t seed, uint64_t stream) {
  karst_rng_derive(rng, seed, stream, 0);
}

/** Seed the sub-stream (seed, stream, substream), e.g. one per pipeline stage. O(1). */
void karst_rng_derive(karst_rng_t *rng, uint64_t seed, uint64_t stream, uint64_t substream) {
  uint64_t x = seed;
  uint64_t h = splitmix64(&x);
  x = h ^ (stream * 0xD1342543DE82EF95ULL + 0x2545F4914F6CDD1DULL);
  h = splitmix64(&x);
  x = h ^ (substream * 0xA0761D6478BD642FULL + 0xE7037ED1A0B428DBULL);
  for (int i = 0; i < 4; i++) rng->s[i] = splitmix64(&x);
  if ((rng->s[0] | rng->s[1] | rng->s[2] | rng->s[3]) == 0) rng->s[0] = 1; /* never all-zero */
}

uint64_t karst_rng_u64(karst_rng_t *rng) {
  uint64_t *s = rng->s;
  const uint64_t result = rotl(s[1] * 5, 7) * 9;
  const uint64_t t = s[1] << 17;
  s[2] ^= s[0];
  s[3] ^= s[1];
  s[1] ^= s[2];
  s[0] ^= s[3];
  s[2] ^= t;
  s[3] = rotl(s[3], 45);
  return result;
}

double karst_rng_uniform(karst_rng_t *rng) {
  return (double)(karst_rng_u64(rng) >> 11) * 0x1.0p-53;
}

double karst_rng_uniform_range(karst_rng_t *rng, double a, double b) {
  return a + (b - a) * karst_rng_uniform(rng);
}

/* Lemire's nearly-divisionless method with rejection: exact uniformity. */
uint64_t karst_rng_below(karst_rng_t *rng, uint64_t n) {
  if (n == 0) return 0;
  __uint128_t m = (__uint128_t)karst_rng_u64(rng) * n;
  uint64_t l = (uint64_t)m;
  if (l < n) {
    uint64_t t = (0 - n) % n;
    while (l < t) {
      m = (__uint128_t)karst_rng_u64(rng) * n;
      l = (uint64_t)m;
    }
  }
  return (uint64_t)(m >> 64);
}

double karst_rng_gaussian(karst_rng_t *rng) {
  double u, v, s;
  do {
    u = 2.0 * karst_rng_uniform(rng) - 1.0;
    v = 2.0 * karst_rng_uniform(rng) - 1.0;
    s = u * u + v * v;
  } while (s >= 1.0 || s == 0.0);
  return u * sqrt(-2.0 * log(s) / s);
}

void karst_rng_unit_vector(karst_rng_t *rng, double v[3]) {
  /* Marsaglia 1972: uniform on the sphere. */
  double a, b, s;
  do {
    a = 2.0 * karst_rng_uniform(rng) - 1.0;
    b = 2.0 * karst_rng_uniform(rng) - 1.0;
    s = a * a + b * b;
  } while (s >= 1.0);
  double r = 2.0 * sqrt(1.0 - s);
  v[0] = a * r;
  v[1] = b * r;
  v[2] = 1.0 - 2.0 * s;
}
