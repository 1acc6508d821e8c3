// SPDX-License-Identifier: MIT
#include "solid/disc_overlaps.hpp"

#include <bit>
#include <cstddef>

#include "solid/touching_pass.hpp"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define TESSERA_DISC_AVX512 1
#endif

namespace tessera {

namespace {

constexpr std::size_t kAhead = kTouchingPrefetch;

// Pairs from `begin` on: the scalar loop of every mirror layout (touching_pass.hpp).
std::size_t scalar_pass(const DiscOverlapPass& p, std::size_t begin, std::size_t count) {
  return find_touching_scalar(p.mirrors, p.first, p.second, begin, p.pairs, count, p.touching, p.was, p.history,
                              [](const DiscMirror& ga, const DiscMirror& gb) {
                                const double du = ga.u - gb.u, dv = ga.v - gb.v, rsum = ga.r + gb.r;
                                return du * du + dv * dv < rsum * rsum;
                              });
}

#ifdef TESSERA_DISC_AVX512
__attribute__((target("avx512f,avx512vl,avx512bw"))) std::size_t avx512_pass(const DiscOverlapPass& p,
                                                                               std::size_t& done) {
  static_assert(sizeof(DiscMirror) == 64 && offsetof(DiscMirror, v) == 8 && offsetof(DiscMirror, r) == 16);
  const double* base = &p.mirrors[0].u;
  // (The masked form: GCC 12's unmasked gather reads an uninitialised source. A macro: a lambda
  // would not take the function's target.)
#define TESSERA_GATHER(index, at) _mm512_mask_i32gather_pd(_mm512_setzero_pd(), 0xff, index, at, 8)
  const __m256i iota = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  std::size_t count = 0, k = 0;
  for (; k + 8 <= p.pairs; k += 8) {
    if (k + kAhead + 8 <= p.pairs)
      for (std::size_t j = 0; j < 8; ++j) __builtin_prefetch(&p.mirrors[p.second[k + kAhead + j]]);
    // Mirror index i -> its line at 8 i doubles from the first u.
    const __m256i a = _mm256_slli_epi32(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(p.first + k)), 3);
    const __m256i b = _mm256_slli_epi32(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(p.second + k)), 3);
    const __m512d du = _mm512_sub_pd(TESSERA_GATHER(a, base), TESSERA_GATHER(b, base));
    const __m512d dv = _mm512_sub_pd(TESSERA_GATHER(a, base + 1), TESSERA_GATHER(b, base + 1));
    const __m512d rs = _mm512_add_pd(TESSERA_GATHER(a, base + 2), TESSERA_GATHER(b, base + 2));
    const __m512d d2 = _mm512_add_pd(_mm512_mul_pd(du, du), _mm512_mul_pd(dv, dv));
    const __mmask8 touch = _mm512_cmp_pd_mask(d2, _mm512_mul_pd(rs, rs), _CMP_LT_OQ);
    const __m256i index = _mm256_add_epi32(_mm256_set1_epi32(static_cast<int>(k)), iota);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(p.touching + count), _mm256_maskz_compress_epi32(touch, index));
    count += static_cast<std::size_t>(std::popcount(static_cast<unsigned>(touch)));
    if (p.was) {
      const __m128i flags = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(p.was + k));
      const __mmask16 was = _mm_test_epi8_mask(flags, flags);
      unsigned opened = static_cast<unsigned>(was) & ~static_cast<unsigned>(touch) & 0xffu;
      while (opened) {  // rare: a contact that opened loses its spring
        const std::size_t j = k + static_cast<std::size_t>(std::countr_zero(opened));
        p.history[3 * j] = p.history[3 * j + 1] = p.history[3 * j + 2] = 0.0;
        opened &= opened - 1;
      }
      _mm_storel_epi64(reinterpret_cast<__m128i*>(p.was + k), _mm_maskz_set1_epi8(touch, 1));
    }
  }
#undef TESSERA_GATHER
  done = k;
  return count;
}
#endif

}  // namespace

std::size_t find_disc_overlaps(const DiscOverlapPass& pass) {
  std::size_t done = 0, count = 0;
#ifdef TESSERA_DISC_AVX512
  static const bool avx512 = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
                             __builtin_cpu_supports("avx512bw");
  if (avx512) count = avx512_pass(pass, done);
#endif
  return scalar_pass(pass, done, count);
}

}  // namespace tessera
