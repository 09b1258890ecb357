/* %.17g without printf (src/io/format_internal.h). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "io/format_internal.h"

#if defined(__SIZEOF_INT128__)
typedef unsigned __int128 u128;

static const uint64_t P10[20] = {1ull,
                                 10ull,
                                 100ull,
                                 1000ull,
                                 10000ull,
                                 100000ull,
                                 1000000ull,
                                 10000000ull,
                                 100000000ull,
                                 1000000000ull,
                                 10000000000ull,
                                 100000000000ull,
                                 1000000000000ull,
                                 10000000000000ull,
                                 100000000000000ull,
                                 1000000000000000ull,
                                 10000000000000000ull,
                                 100000000000000000ull,
                                 1000000000000000000ull,
                                 10000000000000000000ull};

static u128 pow10_u128(int k) { /* 0 <= k <= 38 */
  return k <= 19 ? (u128)P10[k] : (u128)P10[19] * P10[k - 19];
}

/* floor(a 10^k) for a = m 2^e (m < 2^53), into *q, with *half: -1, 0, 1 as the rest is below,
 * at or above one half. 0 when it does not fit the 128-bit range handled here. */
static int scaled(uint64_t m, int e, int k, u128 *q, int *half) {
  if (k >= 0) {
    if (k > 22) return 0; /* m 10^k < 2^53 2^74 = 2^127 */
    u128 num = (u128)m * pow10_u128(k);
    if (e >= 0) {
      if (e > 127 || (num >> (127 - e)) != 0) return 0;
      *q = num << e, *half = -1;
      return 1;
    }
    int s = -e;
    if (s >= 127) return 0;
    u128 rest = num & (((u128)1 << s) - 1), h = (u128)1 << (s - 1);
    *q = num >> s;
    *half = rest < h ? -1 : (rest == h ? 0 : 1);
    return 1;
  }
  if (e < 0 || e > 74 || -k > 38) return 0; /* m 2^e < 2^127 */
  u128 num = (u128)m << e, d = pow10_u128(-k);
  *q = num / d;
  u128 rest = num % d;
  *half = 2 * rest < d ? -1 : (2 * rest == d ? 0 : 1);
  return 1;
}

size_t karst_i_format_g17(double v, char out[KARST_I_G17_SIZE]) {
  double a = fabs(v);
  if (!(a >= 1e-6 && a < 0x1p127)) /* also zero, infinities and NaN */
    return (size_t)snprintf(out, KARST_I_G17_SIZE, "%.17g", v);
  uint64_t bits;
  memcpy(&bits, &a, sizeof bits); /* a is normal: a = m 2^e with the implicit bit in m */
  const uint64_t m = (bits & ((1ull << 52) - 1)) | (1ull << 52);
  const int e = (int)(bits >> 52) - 1075;
  int x = (int)floor((e + 52) * 0.30102999566398120); /* log10 of 2^(e+52): the exponent ± 1 */
  const u128 lo = P10[16], hi = P10[17];
  u128 q;
  int half;
  for (int tries = 0;; tries++) {
    if (tries > 3 || !scaled(m, e, 16 - x, &q, &half))
      return (size_t)snprintf(out, KARST_I_G17_SIZE, "%.17g", v);
    if (q >= hi)
      x++;
    else if (q < lo)
      x--;
    else
      break;
  }
  if (half > 0 || (half == 0 && (q & 1))) q++; /* to nearest, ties to even */
  if (q == hi) q = lo, x++;
  char dig[18];
  uint64_t d = (uint64_t)q; /* < 10^17 */
  for (int i = 16; i >= 0; i--)
    dig[i] = (char)('0' + (int)(d % 10)), d /= 10;
  int nd = 17;
  while (nd > 1 && dig[nd - 1] == '0')
    nd--;
  char *o = out;
  if (signbit(v)) *o++ = '-';
  if (x < -4 || x >= 17) { /* d.ddde±XX */
    *o++ = dig[0];
    if (nd > 1) {
      *o++ = '.';
      memcpy(o, dig + 1, (size_t)(nd - 1)), o += nd - 1;
    }
    *o++ = 'e';
    *o++ = x < 0 ? '-' : '+';
    int ax = x < 0 ? -x : x;
    if (ax >= 100) *o++ = (char)('0' + ax / 100);
    *o++ = (char)('0' + ax / 10 % 10);
    *o++ = (char)('0' + ax % 10);
  } else if (x >= 0) { /* ddd.ddd */
    int ip = x + 1;
    for (int i = 0; i < ip; i++)
      *o++ = i < nd ? dig[i] : '0';
    if (nd > ip) {
      *o++ = '.';
      memcpy(o, dig + ip, (size_t)(nd - ip)), o += nd - ip;
    }
  } else { /* 0.000ddd */
    *o++ = '0';
    *o++ = '.';
    for (int i = 0; i < -x - 1; i++)
      *o++ = '0';
    memcpy(o, dig, (size_t)nd), o += nd;
  }
  *o = '\0';
  return (size_t)(o - out);
}
#else /* no 128-bit integers: printf itself */
size_t karst_i_format_g17(double v, char out[KARST_I_G17_SIZE]) {
  return (size_t)snprintf(out, KARST_I_G17_SIZE, "%.17g", v);
}
#endif
