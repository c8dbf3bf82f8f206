/* The STD lobe's D V over four observations at once (tailed.h, "The lobe
 * over a block"; docs/model.md §2.8, "Cost"): the general regime's std_dv
 * in the four lanes of an AVX2 vector where the processor has AVX2 and FMA
 * (asked at run time: only these functions are compiled for it, the build
 * stays baseline x86-64), else std_dv four times. With an exp and a log1p
 * of its own: libm has no inline vector form. No FMA where a sum must stay
 * symmetric in l and v (reciprocity to the bit): c_o L_i + c_i L_o. */
#include "tailed.h"

#if defined(__x86_64__) && defined(__GNUC__)
#define CF_STD_BLOCK_AVX2 1
#include <immintrin.h>
#define CF_AVX2 __attribute__((target("avx2,fma")))
#define CF_AVX2_INLINE static inline __attribute__((always_inline, target("avx2,fma")))
#endif

static void block_scalar(const cf_std_tail *t, const cf_std_table *tb, const cf_std_block_in *in,
                         int with_grad, cf_std_dv_block *out) {
  for (int k = 0; k < CF_STD_BLOCK; ++k) {
    cf_std_dv s =
        cf_std_dv_eval(t, tb, in->sin2[k], in->cos2[k], in->c_i[k], in->c_o[k], with_grad);
    out->value[k] = s.value;
    out->d_a2[k] = s.d_a2;
    out->d_gamma[k] = s.d_gamma;
    out->d_sin2[k] = s.d_sin2;
    out->d_ci[k] = s.d_ci;
    out->d_co[k] = s.d_co;
  }
}

#ifdef CF_STD_BLOCK_AVX2

typedef __m256d v4d;
typedef __m256i v4i;

CF_AVX2_INLINE v4d vset(double x) {
  return _mm256_set1_pd(x);
}
CF_AVX2_INLINE v4d vadd(v4d a, v4d b) {
  return _mm256_add_pd(a, b);
}
CF_AVX2_INLINE v4d vsub(v4d a, v4d b) {
  return _mm256_sub_pd(a, b);
}
CF_AVX2_INLINE v4d vmul(v4d a, v4d b) {
  return _mm256_mul_pd(a, b);
}
CF_AVX2_INLINE v4d vdiv(v4d a, v4d b) {
  return _mm256_div_pd(a, b);
}
CF_AVX2_INLINE v4d vfma(v4d a, v4d b, v4d c) { /* a b + c, one rounding */
  return _mm256_fmadd_pd(a, b, c);
}
/* m ? b : a */
CF_AVX2_INLINE v4d vsel(v4d m, v4d a, v4d b) {
  return _mm256_blendv_pd(a, b, m);
}

/* 2^k for integral k in [−1022, 1023] held in a double: the bits of
 * k + 1023 + 2^52 are 0x4330... + (k + 1023), shifted into the exponent */
CF_AVX2_INLINE v4d vpow2(v4d k) {
  v4i bits = _mm256_castpd_si256(vadd(k, vset(1023.0 + 0x1p52)));
  return _mm256_castsi256_pd(_mm256_slli_epi64(bits, 52));
}

/* exp(y) for y <= 0 (the lobe's r^γ, r <= 1): y = n ln 2 + r, |r| <= ln2/2,
 * the Taylor polynomial of degree 13 in r (truncation < 5e-18), 2^n as two
 * factors so that subnormal results are right; 0 below −745.2 (as libm).
 * Within 1 ulp of libm's exp over [−745, 0] (test_tailed_lobe). */
CF_AVX2_INLINE v4d vexp(v4d y) {
  static const double inv_fact[14] = {
      1.0,
      1.0,
      1.0 / 2.0,
      1.0 / 6.0,
      1.0 / 24.0,
      1.0 / 120.0,
      1.0 / 720.0,
      1.0 / 5040.0,
      1.0 / 40320.0,
      1.0 / 362880.0,
      1.0 / 3628800.0,
      1.0 / 39916800.0,
      1.0 / 479001600.0,
      1.0 / 6227020800.0,
  };
  v4d underflow = _mm256_cmp_pd(y, vset(-745.2), _CMP_LT_OQ);
  y = _mm256_max_pd(y, vset(-745.2));
  v4d n = _mm256_round_pd(vmul(y, vset(1.4426950408889634074)),
                          _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
  v4d r = vfma(n, vset(-6.93147180369123816490e-01), y); /* ln 2 = hi + lo (fdlibm's) */
  r = vfma(n, vset(-1.90821492927058770002e-10), r);
  v4d p = vset(inv_fact[13]);
  for (int k = 12; k >= 0; --k) p = vfma(p, r, vset(inv_fact[k]));
  v4d n1 = _mm256_floor_pd(vmul(n, vset(0.5))), n2 = vsub(n, n1);
  v4d e = vmul(vmul(p, vpow2(n1)), vpow2(n2));
  return _mm256_andnot_pd(underflow, e);
}

/* ln(1 + x) for 0 <= x < 2^1023 (x = tan²θ_h/β²): 1 + x = 2^k m, m in
 * [√2/2, √2), log m as fdlibm's e_log.c (s = f/(2 + f), its Remez
 * polynomial R, error < 2^−58.45), and the rounding of 1 + x put back as
 * (x − (u − 1))/u (fdlibm's s_log1p.c): log1p's accuracy at every x.
 * Within 1 ulp of libm's log1p (test_tailed_lobe). */
CF_AVX2_INLINE v4d vlog1p(v4d x) {
  const double lg1 = 6.666666666666735130e-01, lg2 = 3.999999999940941908e-01,
               lg3 = 2.857142874366239149e-01, lg4 = 2.222219843214978396e-01,
               lg5 = 1.818357216161805012e-01, lg6 = 1.531383769920937332e-01,
               lg7 = 1.479819860511658591e-01;
  v4d u = vadd(vset(1.0), x);
  v4d c = vdiv(vsub(x, vsub(u, vset(1.0))), u);
  /* k and m as fdlibm's: adding 0x3ff00000 − 0x3fe6a09e (√2/2's high word)
   * to u's high word carries into the exponent where m would be >= √2 */
  v4i ix = _mm256_add_epi64(_mm256_castpd_si256(u), _mm256_set1_epi64x(0x00095f6200000000ll));
  v4i hk = _mm256_srli_epi64(ix, 52); /* k + 1023 */
  v4i mb = _mm256_add_epi64(_mm256_and_si256(ix, _mm256_set1_epi64x(0x000fffffffffffffll)),
                            _mm256_set1_epi64x(0x3fe6a09e00000000ll));
  v4d k = vsub(_mm256_castsi256_pd(_mm256_or_si256(hk, _mm256_set1_epi64x(0x4330000000000000ll))),
               vset(0x1p52 + 1023.0));
  v4d f = vsub(_mm256_castsi256_pd(mb), vset(1.0));
  v4d s = vdiv(f, vadd(vset(2.0), f));
  v4d z = vmul(s, s), w = vmul(z, z);
  v4d t1 = vmul(w, vfma(w, vfma(w, vset(lg6), vset(lg4)), vset(lg2)));
  v4d t2 = vmul(z, vfma(w, vfma(w, vfma(w, vset(lg7), vset(lg5)), vset(lg3)), vset(lg1)));
  v4d rr = vadd(t2, t1), hfsq = vmul(vmul(vset(0.5), f), f);
  /* k ln2_hi − ((hfsq − (s (hfsq + R) + (k ln2_lo + c))) − f) */
  v4d lo = vfma(k, vset(1.90821492927058770002e-10), c);
  v4d inner = vsub(vsub(hfsq, vfma(s, vadd(hfsq, rr), lo)), f);
  return vsub(vmul(k, vset(6.93147180369123816490e-01)), inner);
}

/* D of std_d (tailed.h) in the general regime */
typedef struct vd {
  v4d value, d_a2, d_gamma, d_sin2;
} vd;

CF_AVX2_INLINE vd vstd_d(const cf_std_tail *t, v4d sin2, v4d cos2, int with_grad) {
  vd d;
  v4d lit = _mm256_cmp_pd(cos2, vset(0.0), _CMP_GT_OQ);
  v4d floored = _mm256_cmp_pd(cos2, vset(CF_STD_COS2_MIN), _CMP_LT_OQ);
  cos2 = vsel(floored, cos2, vset(CF_STD_COS2_MIN));
  sin2 = vsel(floored, sin2, vset(1.0 - CF_STD_COS2_MIN));
  v4d b2 = vset(t->b2), gamma = vset(t->gamma), inv_a2 = vset(t->inv_a2);
  v4d b2c = vmul(b2, cos2);
  v4d x = vdiv(sin2, b2c);
  v4d q = vadd(sin2, b2c), inv_qc = vdiv(vset(1.0), vmul(q, cos2));
  v4d inv_cos2 = vmul(q, inv_qc);
  v4d ln_r = vsub(vset(0.0), vlog1p(x));
  d.value =
      vmul(vmul(vexp(vmul(gamma, ln_r)), vmul(inv_cos2, inv_cos2)), vmul(inv_a2, vset(CF_INV_PI)));
  d.value = _mm256_and_pd(lit, d.value);
  if (!with_grad) return d;
  v4d sin2_over_q = vmul(vmul(sin2, cos2), inv_qc);
  v4d g_s = vmul(gamma, sin2_over_q);
  d.d_a2 = vmul(vmul(d.value, vsub(g_s, vset(1.0))), inv_a2);
  d.d_gamma = vmul(d.value, vadd(ln_r, vmul(g_s, vset(t->inv_a))));
  v4d d_sin2 = vmul(vmul(vsub(vset(0.0), d.value), vsub(gamma, vmul(vset(2.0), q))), inv_qc);
  d.d_sin2 = _mm256_andnot_pd(floored, d_sin2);
  return d;
}

/* The table's lookup (std_table_lookup) of four w: the octave j from the
 * exponent, the step i from the mantissa; the steps' coefficients loaded
 * and transposed. */
typedef struct vg {
  v4d g, g_w, g_gamma;
} vg;

CF_AVX2_INLINE void transpose4(v4d a, v4d b, v4d c, v4d d, v4d out[4]) {
  v4d ab_lo = _mm256_unpacklo_pd(a, b), ab_hi = _mm256_unpackhi_pd(a, b);
  v4d cd_lo = _mm256_unpacklo_pd(c, d), cd_hi = _mm256_unpackhi_pd(c, d);
  out[0] = _mm256_permute2f128_pd(ab_lo, cd_lo, 0x20);
  out[1] = _mm256_permute2f128_pd(ab_hi, cd_hi, 0x20);
  out[2] = _mm256_permute2f128_pd(ab_lo, cd_lo, 0x31);
  out[3] = _mm256_permute2f128_pd(ab_hi, cd_hi, 0x31);
}

CF_AVX2_INLINE vg vtable_lookup(const cf_std_table *tb, v4d w, int with_grad) {
  const v4i fraction = _mm256_set1_epi64x(0x000FFFFFFFFFFFFFll);
  const v4i one = _mm256_set1_epi64x(0x3FF0000000000000ll);
  v4d first = _mm256_cmp_pd(w, vset(1.0), _CMP_NLT_UQ); /* u = 0: step 0 at t = 1 */
  v4d linear = _mm256_andnot_pd(first, _mm256_cmp_pd(w, vset(0x1p-46), _CMP_NGE_UQ));
  v4d special = _mm256_or_pd(first, linear);
  v4d wg = vsel(special, w, vset(0.75)); /* a harmless w where the octaves do not apply */
  v4i bits = _mm256_castpd_si256(wg);
  v4i j = _mm256_sub_epi64(_mm256_set1_epi64x(1022), _mm256_srli_epi64(bits, 52));
  /* octave j's 2^k steps and its last step, first[j] + 2^k − 1, from the
   * octave tables lane by lane */
  long long jj[CF_STD_BLOCK], kk[CF_STD_BLOCK], end[CF_STD_BLOCK], ii[CF_STD_BLOCK];
  _mm256_storeu_si256((v4i *)jj, j);
  for (int l = 0; l < CF_STD_BLOCK; ++l) {
    kk[l] = cf_std_octave_log2_steps[jj[l]];
    end[l] = cf_std_octave_first[jj[l]] + (1 << kk[l]) - 1;
  }
  v4i k = _mm256_loadu_si256((const v4i *)kk);
  v4i f = _mm256_and_si256(bits, fraction);
  v4i i = _mm256_srlv_epi64(f, _mm256_sub_epi64(_mm256_set1_epi64x(52), k));
  v4d t = vsub(_mm256_castsi256_pd(
                   _mm256_or_si256(_mm256_and_si256(_mm256_sllv_epi64(f, k), fraction), one)),
               vset(1.0));
  /* 1/h = 2^(k + j + 1) */
  v4d inv_h = _mm256_castsi256_pd(
      _mm256_slli_epi64(_mm256_add_epi64(_mm256_add_epi64(k, j), _mm256_set1_epi64x(1024)), 52));
  /* the first node: step 0 at t = 1 */
  t = vsel(first, t, vset(1.0));
  inv_h = vsel(first, inv_h, vset((1 << cf_std_octave_log2_steps[0]) * 2.0));
  _mm256_storeu_si256((v4i *)ii, i);
  int firsts = _mm256_movemask_pd(first), sf[CF_STD_BLOCK];
  for (int l = 0; l < CF_STD_BLOCK; ++l) sf[l] = firsts >> l & 1 ? 0 : (int)(end[l] - ii[l]);
  const cf_std_step *st = tb->step;
  v4d c[4];
  transpose4(_mm256_loadu_pd(st[sf[0]].c), _mm256_loadu_pd(st[sf[1]].c),
             _mm256_loadu_pd(st[sf[2]].c), _mm256_loadu_pd(st[sf[3]].c), c);
  vg r;
  r.g = vfma(t, vfma(t, vfma(t, c[3], c[2]), c[1]), c[0]);
  if (with_grad) {
    v4d d[4];
    transpose4(_mm256_loadu_pd(st[sf[0]].d), _mm256_loadu_pd(st[sf[1]].d),
               _mm256_loadu_pd(st[sf[2]].d), _mm256_loadu_pd(st[sf[3]].d), d);
    r.g_gamma = vfma(t, vfma(t, vfma(t, d[3], d[2]), d[1]), d[0]);
    r.g_w = vmul(vfma(t, vfma(vmul(vset(3.0), t), c[3], vmul(vset(2.0), c[2])), c[1]), inv_h);
  }
  { /* linear to g(0) = 1 below w = 2^−46 */
    const cf_std_step *last = &st[CF_STD_TABLE_STEPS - 1];
    double slope = (last->c[0] - 1.0) * 0x1p46;
    v4d w0 = _mm256_max_pd(w, vset(0.0)); /* w < 0 (c = 1 + ulp): 0; NaN: 0 */
    w0 = _mm256_and_pd(_mm256_cmp_pd(w, vset(0.0), _CMP_GT_OQ), w0);
    r.g = vsel(linear, r.g, vadd(vset(1.0), vmul(vset(slope), w0)));
    if (with_grad) {
      r.g_w = vsel(linear, r.g_w, vset(slope));
      r.g_gamma = vsel(linear, r.g_gamma, vmul(vset(last->d[0]), vmul(w0, vset(0x1p46))));
    }
  }
  return r;
}

/* std_masking_tabulated of four cosines */
typedef struct vm {
  v4d value, d_c, d_a2, d_gamma;
} vm;

CF_AVX2_INLINE vm vmasking(const cf_std_table *tb, double a2_s, v4d c, int with_grad) {
  vm m;
  v4d a2 = vset(a2_s), one = vset(1.0), one_m_a2 = vset(1.0 - a2_s);
  v4d s2 = vmul(vsub(one, c), vadd(one, c));
  v4d q = vadd(a2, vmul(vmul(c, c), one_m_a2));
  v4d inv_q = vdiv(one, q), sqrt_q = _mm256_sqrt_pd(q);
  vg g = vtable_lookup(tb, vmul(vmul(s2, a2), inv_q), with_grad);
  m.value = vmul(sqrt_q, g.g);
  if (!with_grad) return m;
  v4d inv_sqrt_q = vmul(sqrt_q, inv_q), g_w_q = vmul(g.g_w, inv_q);
  m.d_c = vmul(vmul(c, inv_sqrt_q), vsub(vmul(one_m_a2, g.g), vmul(vmul(vset(2.0), a2), g_w_q)));
  m.d_a2 = vmul(vmul(vmul(vset(0.5), s2), inv_sqrt_q),
                vadd(g.g, vmul(vmul(vmul(vset(2.0), c), c), g_w_q)));
  m.d_gamma = vmul(sqrt_q, g.g_gamma);
  return m;
}

CF_AVX2_INLINE void block_avx2_body(const cf_std_tail *t, const cf_std_table *tb,
                                    const cf_std_block_in *in, int with_grad,
                                    cf_std_dv_block *out) {
  v4d ci = _mm256_loadu_pd(in->c_i), co = _mm256_loadu_pd(in->c_o);
  vd d = vstd_d(t, _mm256_loadu_pd(in->sin2), _mm256_loadu_pd(in->cos2), with_grad);
  vm mi = vmasking(tb, t->a2, ci, with_grad), mo = vmasking(tb, t->a2, co, with_grad);
  /* V = 1/(2 (c_o L_i + c_i L_o)): products then a sum, symmetric in i, o to the bit */
  v4d v = vdiv(vset(0.5), vadd(vmul(co, mi.value), vmul(ci, mo.value)));
  _mm256_storeu_pd(out->value, vmul(d.value, v));
  if (!with_grad) return;
  v4d v2 = vmul(vmul(vset(-2.0), v), v); /* ∂V/∂(c_o L_i + c_i L_o) */
  v4d dv_a2 = vmul(v2, vadd(vmul(co, mi.d_a2), vmul(ci, mo.d_a2)));
  v4d dv_gamma = vmul(v2, vadd(vmul(co, mi.d_gamma), vmul(ci, mo.d_gamma)));
  v4d dv_ci = vmul(v2, vadd(mo.value, vmul(co, mi.d_c)));
  v4d dv_co = vmul(v2, vadd(mi.value, vmul(ci, mo.d_c)));
  _mm256_storeu_pd(out->d_a2, vadd(vmul(d.d_a2, v), vmul(d.value, dv_a2)));
  _mm256_storeu_pd(out->d_gamma, vadd(vmul(d.d_gamma, v), vmul(d.value, dv_gamma)));
  _mm256_storeu_pd(out->d_sin2, vmul(d.d_sin2, v));
  _mm256_storeu_pd(out->d_ci, vmul(d.value, dv_ci));
  _mm256_storeu_pd(out->d_co, vmul(d.value, dv_co));
}

/* one or two lobes (M4T's film and base) in one body, so that the
 * processor overlaps their chains */
CF_AVX2 static void block_avx2_grad(const cf_std_tail *t, const cf_std_table *tb, int lobes,
                                    const cf_std_block_in *in, cf_std_dv_block *out) {
  block_avx2_body(&t[0], tb, &in[0], 1, &out[0]);
  if (lobes > 1) block_avx2_body(&t[1], tb, &in[1], 1, &out[1]);
}

CF_AVX2 static void block_avx2_value(const cf_std_tail *t, const cf_std_table *tb, int lobes,
                                     const cf_std_block_in *in, cf_std_dv_block *out) {
  block_avx2_body(&t[0], tb, &in[0], 0, &out[0]);
  if (lobes > 1) block_avx2_body(&t[1], tb, &in[1], 0, &out[1]);
}

CF_AVX2 static void vexp4(const double *y, double *out) {
  _mm256_storeu_pd(out, vexp(_mm256_loadu_pd(y)));
}
CF_AVX2 static void vlog1p4(const double *x, double *out) {
  _mm256_storeu_pd(out, vlog1p(_mm256_loadu_pd(x)));
}
#endif /* CF_STD_BLOCK_AVX2 */

void cf_std_block_exp(const double y[CF_STD_BLOCK], double out[CF_STD_BLOCK]) {
#ifdef CF_STD_BLOCK_AVX2
  if (cf_std_block_vector()) {
    vexp4(y, out);
    return;
  }
#endif
  for (int k = 0; k < CF_STD_BLOCK; ++k) out[k] = exp(y[k]);
}

void cf_std_block_log1p(const double x[CF_STD_BLOCK], double out[CF_STD_BLOCK]) {
#ifdef CF_STD_BLOCK_AVX2
  if (cf_std_block_vector()) {
    vlog1p4(x, out);
    return;
  }
#endif
  for (int k = 0; k < CF_STD_BLOCK; ++k) out[k] = log1p(x[k]);
}

int cf_std_block_vector(void) {
#ifdef CF_STD_BLOCK_AVX2
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
  return 0;
#endif
}

void cf_std_dv_block_eval(const cf_std_tail *t, const cf_std_table *tb, int vector, int lobes,
                          const cf_std_block_in *in, int with_grad, cf_std_dv_block *out) {
#ifdef CF_STD_BLOCK_AVX2
  if (vector && t[0].regime == CF_STD_GENERAL && (lobes < 2 || t[1].regime == CF_STD_GENERAL)) {
    if (with_grad)
      block_avx2_grad(t, tb, lobes, in, out);
    else
      block_avx2_value(t, tb, lobes, in, out);
    return;
  }
#else
  (void)vector;
#endif
  for (int l = 0; l < lobes; ++l) block_scalar(&t[l], tb, &in[l], with_grad, &out[l]);
}
