#include "realtime/sss_pass.h"

#include "core/cpu_dispatch.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace ssslab::realtime {

SssGBuffer::SssGBuffer(int w, int h)
    : width(w),
      height(h),
      irradiance(static_cast<size_t>(w) * static_cast<size_t>(h) * 3, 0.0f),
      view_z(static_cast<size_t>(w) * static_cast<size_t>(h), 1.0f),
      material(static_cast<size_t>(w) * static_cast<size_t>(h), 0) {}

SssMaterialKernel make_material_kernel(const std::array<const approx::SeparableKernel*, 3>& a,
                                       int count, double support_mass) {
    for (int ch = 0; ch < 3; ++ch) {
        if (!a[ch]) throw std::invalid_argument("make_material_kernel: null kernel");
        if (a[ch]->rank() != a[0]->rank())
            throw std::invalid_argument("make_material_kernel: the channels differ in rank");
    }
    SssMaterialKernel k;
    for (int t = 0; t < a[0]->rank(); ++t) {
        SssTerm term;
        term.taps = approx::make_term_taps(a, t, count, support_mass);
        for (int ch = 0; ch < 3; ++ch)
            term.sign[ch] = a[ch]->terms[static_cast<size_t>(t)].sign < 0 ? -1.0 : 1.0;
        k.terms.push_back(std::move(term));
    }
    return k;
}

void check_sss_inputs(const SssGBuffer& g, const std::vector<SssMaterialKernel>& materials,
                      const SssParams& p) {
    if (g.width < 1 || g.height < 1) throw std::invalid_argument("sss_pass: empty G-buffer");
    const size_t n = g.pixels();
    if (g.irradiance.size() != 3 * n || g.view_z.size() != n || g.material.size() != n)
        throw std::invalid_argument("sss_pass: G-buffer arrays differ from width x height");
    if (!(p.tan_half > 0) || !std::isfinite(p.tan_half))
        throw std::invalid_argument("sss_pass: tan_half must be > 0");
    if (!(p.aspect > 0) || !std::isfinite(p.aspect))
        throw std::invalid_argument("sss_pass: aspect must be > 0");
    if (!(p.unit_mm > 0) || !std::isfinite(p.unit_mm))
        throw std::invalid_argument("sss_pass: unit_mm must be > 0");
    if (!(p.follow_strength >= 0)) throw std::invalid_argument("sss_pass: follow_strength < 0");
    if (!(p.reject_depth >= 0)) throw std::invalid_argument("sss_pass: reject_depth < 0");
    if (!(p.jitter >= 0) || !std::isfinite(p.jitter))
        throw std::invalid_argument("sss_pass: jitter must be >= 0");
    for (const SssMaterialKernel& m : materials)
        for (const SssTerm& t : m.terms) {
            if (t.taps.offset_mm.empty())
                throw std::invalid_argument("sss_pass: a term has no taps");
            for (int ch = 0; ch < 3; ++ch)
                if (t.taps.weight[ch].size() != t.taps.offset_mm.size())
                    throw std::invalid_argument("sss_pass: weights and offsets differ in length");
        }
}

void refuse_sss_pixel(const SssGBuffer& g, size_t materials, size_t i) {
    const int32_t m = g.material[i];
    if (m < -1 || m >= static_cast<int32_t>(materials))
        throw std::invalid_argument("sss_pass: material index " + std::to_string(m) +
                                    " without a kernel");
    throw std::invalid_argument("sss_pass: a medium pixel has no positive finite depth");
}

namespace {

// A texel of a pass's input: R, G, B and the view z in the fourth lane, so that one 16-byte
// load fetches everything a tap needs (GCC vector extension: SSE2 on any x86-64).
typedef float F4 __attribute__((vector_size(16)));
typedef int32_t I4 __attribute__((vector_size(16)));
inline F4 abs4(F4 v) {
    I4 bits;
    std::memcpy(&bits, &v, sizeof bits);
    bits &= 0x7fffffff;
    std::memcpy(&v, &bits, sizeof v);
    return v;
}

// One term's taps prepared for the pass.
struct PreparedTerm {
    const SssTerm* term = nullptr;
    approx::TapJitterRange range;
    std::array<double, 3> weight_sum{};
    std::vector<F4> weight;       ///< per tap (R, G, B, 0) as floats
    double lo_mm = 0, hi_mm = 0;  ///< the extreme offsets a tap can reach (with jitter)
};

// What one 1D pass needs besides the line it reads.
struct LineParams {
    float follow = 0;        ///< follow_strength / tan_half
    float reject_depth = 0;  ///< kReject's largest depth difference
    uint32_t seed = 0;
};

// The texels a 1D pass reads: a row of the G-buffer (irradiance and view z read in place) or a
// column of the horizontal pass's result (R, G, B, z texels, contiguous).
struct ColumnLine {
    const F4* t;
    int first = 0;  ///< the position of t[0]
    F4 texel(int q) const { return t[q - first]; }
    const F4* at(int q) const { return t + (q - first); }
    float depth(int q) const { return t[q - first][3]; }
};

// One output pixel of a 1D pass of term pt at position pos of a line (a row, or a column of the
// transposed image) of len texels: the rules of the file comment of sss_pass.h, per texel.
// `line` holds R, G, B, z per texel, the materials along the line are mat[pos * mstride];
// (x, y, pass) feed the jitter hash. Inside: every tap position lies within [0, len - 1), so no
// clamping is needed. In chunks of up to kChunk taps: the texel indices and interpolation
// weights of all taps first, then the edge rule's per-texel weights (loops over taps that GCC
// vectorises), then one 16-byte load per texel and the weighted sums.
constexpr size_t kChunk = 32;

// The common case in its own loop: a tap that needs no clamping, no jitter, follow-surface or
// no edge rule. One 32-byte load fetches both texels of a tap (i1 = i0 + 1 inside), as
// (q0 | q1), and the per-texel weights are computed in the same lanes, so a tap costs a few
// 8-wide operations. The arithmetic is filter_pixel's, operation for operation (the same
// roundings in the same order, even taps in one accumulator and odd in the other), so both give
// the same bits; compiled for AVX2 too, chosen at run time (the results do not depend on it).
typedef float F8 __attribute__((vector_size(32)));
typedef int32_t I8 __attribute__((vector_size(32)));

// One tap of the fast loops: both texels (q0 | q1) at tc + rel with weights (1 - a1, a1), the
// follow-surface share to the centre in `ex` [Freude14 Eq. 4.12: s = min(1, follow |z - z_c|)
// per texel], the weighted texels in `ac`.
template <bool Follow>
__attribute__((always_inline)) inline void fast_tap(const F4* tc, int rel, float a1, const F8& zc8,
                                                    const F8& follow8, const F8& one8, const F4& w,
                                                    F4& ac, F4& ex) {
    F8 q;
    std::memcpy(&q, tc + rel, sizeof q);  // (q0 | q1)
    const float a0 = 1 - a1;
    F8 a = {a0, a0, a0, a0, a1, a1, a1, a1};
    if constexpr (Follow) {
        const F8 z = __builtin_shufflevector(q, q, 3, 3, 3, 3, 7, 7, 7, 7);
        F8 k = z - zc8;
        I8 bits;
        std::memcpy(&bits, &k, sizeof bits);
        bits &= 0x7fffffff;
        std::memcpy(&k, &bits, sizeof k);
        k = follow8 * k;
        const F8 t = k < one8 ? k : one8;  // NaN and inf: 1, as std::min(1, k)
        const F8 bb = a * t;
        a *= one8 - t;
        const F4 b4 = __builtin_shufflevector(bb, bb, 0, 1, 2, 3) +
                      __builtin_shufflevector(bb, bb, 4, 5, 6, 7);
        ex += w * b4;
    } else {
        (void)zc8;
        (void)ex;
    }
    const F8 pq = a * q;
    ac += w * (__builtin_shufflevector(pq, pq, 0, 1, 2, 3) +
               __builtin_shufflevector(pq, pq, 4, 5, 6, 7));
}

template <bool Follow>
__attribute__((always_inline)) inline F4 fast_pixel_body(const F4* tc, int pos, const double* off,
                                                         const F4* wt, size_t count, double scale,
                                                         float follow) {
    const F4 centre = tc[0];
    const float zc = centre[3];
    F4 acc0{}, acc1{}, extra0{}, extra1{};
    const F8 zc8 = F8{} + zc, follow8 = F8{} + follow, one8 = F8{} + 1.0f;
    for (size_t begin = 0; begin < count; begin += kChunk) {
        const size_t m = std::min(kChunk, count - begin);
        int rel[kChunk];
        float a1s[kChunk];
        // approx::tap_texels's rule inside the line: i0 = floor(s), t = s - i0.
        for (size_t j = 0; j < m; ++j) {
            const double sp = pos + off[begin + j] * scale;
            const int i0 = static_cast<int>(sp);
            rel[j] = i0 - pos;
            a1s[j] = static_cast<float>(sp - i0);
        }
        auto tap = [&](size_t j, F4 & ac, F4 & ex) __attribute__((always_inline)) {
            fast_tap<Follow>(tc, rel[j], a1s[j], zc8, follow8, one8, wt[begin + j], ac, ex);
        };
        size_t j = 0;
        for (; j + 1 < m; j += 2) {
            tap(j, acc0, extra0);
            tap(j + 1, acc1, extra1);
        }
        if (j < m) tap(j, acc0, extra0);
    }
    F4 out = acc0 + acc1;
    if constexpr (Follow) out += (extra0 + extra1) * centre;
    return out;
}

// Two pixels of a line with the same term at once (their taps interleaved): the same operations
// per pixel as fast_pixel_body, so the same bits; about 1.8 x faster a tap than one pixel at a
// time on this project's machine (measured: the chains of one pixel alone leave the core idle).
template <bool Follow>
__attribute__((always_inline)) inline void fast_pair_body(const F4* tca, int pa, double sa,
                                                          const F4* tcb, int pb, double sb,
                                                          const double* off, const F4* wt,
                                                          size_t count, float follow, F4* out) {
    const F4 ca = tca[0], cb = tcb[0];
    const F8 za8 = F8{} + ca[3], zb8 = F8{} + cb[3], follow8 = F8{} + follow, one8 = F8{} + 1.0f;
    F4 acc_a0{}, acc_a1{}, ex_a0{}, ex_a1{}, acc_b0{}, acc_b1{}, ex_b0{}, ex_b1{};
    for (size_t begin = 0; begin < count; begin += kChunk) {
        const size_t m = std::min(kChunk, count - begin);
        int rel_a[kChunk], rel_b[kChunk];
        float t_a[kChunk], t_b[kChunk];
        for (size_t j = 0; j < m; ++j) {
            const double spa = pa + off[begin + j] * sa;
            const int ia = static_cast<int>(spa);
            rel_a[j] = ia - pa;
            t_a[j] = static_cast<float>(spa - ia);
            const double spb = pb + off[begin + j] * sb;
            const int ib = static_cast<int>(spb);
            rel_b[j] = ib - pb;
            t_b[j] = static_cast<float>(spb - ib);
        }
        auto tap = [&](const F4* tc, int rel, float a1, const F8& zc8, const F4& w, F4& ac, F4& ex)
            __attribute__((always_inline)) {
            fast_tap<Follow>(tc, rel, a1, zc8, follow8, one8, w, ac, ex);
        };
        size_t j = 0;
        for (; j + 1 < m; j += 2) {
            const F4 w0 = wt[begin + j], w1 = wt[begin + j + 1];
            tap(tca, rel_a[j], t_a[j], za8, w0, acc_a0, ex_a0);
            tap(tcb, rel_b[j], t_b[j], zb8, w0, acc_b0, ex_b0);
            tap(tca, rel_a[j + 1], t_a[j + 1], za8, w1, acc_a1, ex_a1);
            tap(tcb, rel_b[j + 1], t_b[j + 1], zb8, w1, acc_b1, ex_b1);
        }
        if (j < m) {
            const F4 w0 = wt[begin + j];
            tap(tca, rel_a[j], t_a[j], za8, w0, acc_a0, ex_a0);
            tap(tcb, rel_b[j], t_b[j], zb8, w0, acc_b0, ex_b0);
        }
    }
    out[0] = acc_a0 + acc_a1;
    out[1] = acc_b0 + acc_b1;
    if constexpr (Follow) {
        out[0] += (ex_a0 + ex_a1) * ca;
        out[1] += (ex_b0 + ex_b1) * cb;
    }
}

SSSLAB_AVX2_CLONES void fast_pair_follow(const F4* tca, int pa, double sa, const F4* tcb, int pb,
                                         double sb, const double* off, const F4* wt, size_t count,
                                         float follow, F4* out) {
    fast_pair_body<true>(tca, pa, sa, tcb, pb, sb, off, wt, count, follow, out);
}
SSSLAB_AVX2_CLONES void fast_pair_none(const F4* tca, int pa, double sa, const F4* tcb, int pb,
                                       double sb, const double* off, const F4* wt, size_t count,
                                       float follow, F4* out) {
    fast_pair_body<false>(tca, pa, sa, tcb, pb, sb, off, wt, count, follow, out);
}

SSSLAB_AVX2_CLONES F4 fast_pixel_follow(const F4* tc, int pos, const double* off, const F4* wt,
                                        size_t count, double scale, float follow) {
    return fast_pixel_body<true>(tc, pos, off, wt, count, scale, follow);
}
SSSLAB_AVX2_CLONES F4 fast_pixel_none(const F4* tc, int pos, const double* off, const F4* wt,
                                      size_t count, double scale, float follow) {
    return fast_pixel_body<false>(tc, pos, off, wt, count, scale, follow);
}

template <SssEdgeMode M, bool Jitter, bool Inside, class Line>
F4 filter_pixel(const Line& line, const int32_t* mat, ptrdiff_t mstride, int len, int pos,
                const PreparedTerm& pt, double scale, const LineParams& lp, int x, int y,
                int pass) {
    const approx::TapKernel& taps = pt.term->taps;
    if constexpr (Inside && !Jitter && M != SssEdgeMode::kReject) {
        (void)mat;
        (void)mstride;
        (void)len;
        (void)x;
        (void)y;
        (void)pass;
        return (M == SssEdgeMode::kFollowSurface ? fast_pixel_follow : fast_pixel_none)(
            line.at(pos), pos, taps.offset_mm.data(), pt.weight.data(), taps.offset_mm.size(),
            scale, lp.follow);
    }
    const F4 centre = line.texel(pos);
    const float zc = centre[3];
    const int32_t mc = mat[pos * mstride];
    // Two accumulators each (even and odd taps) to shorten the dependency chains.
    F4 acc0{}, acc1{}, extra0{}, extra1{};  // extra: follow's centre weight, reject's kept weight
    bool dropped = false;
    const size_t count = taps.offset_mm.size();
    int i0[kChunk], i1[kChunk];
    alignas(16) float a0[kChunk], a1[kChunk], b[kChunk];
    for (size_t begin = 0; begin < count; begin += kChunk) {
        const size_t m = std::min(kChunk, count - begin);
        // Texels and interpolation weights (approx::tap_texels's rule).
        for (size_t j = 0; j < m; ++j) {
            const size_t i = begin + j;
            double o = taps.offset_mm[i];
            if constexpr (Jitter)
                o = approx::jittered_offset_mm(
                    taps, pt.range, i,
                    approx::jitter_hash(x, y, pass, static_cast<int>(i), lp.seed));
            const double s = pos + o * scale;
            double t;
            if constexpr (Inside) {
                i0[j] = static_cast<int>(s);
                i1[j] = i0[j] + 1;
                t = s - i0[j];
            } else {
                const approx::TapTexels tt = approx::tap_texels(s, len);
                i0[j] = tt.i0;
                i1[j] = tt.i1;
                t = tt.t;
            }
            a1[j] = static_cast<float>(t);
            a0[j] = 1 - a1[j];
        }
        // The edge rule's weights per texel.
        if constexpr (M == SssEdgeMode::kFollowSurface) {
            // [Freude14 Eq. 4.12]: s_c = o_c (1 - t) + i_c t, the centre's share b summed apart;
            // four taps at a time (the chunk padded with taps of weight 0 at the centre's depth).
            alignas(16) float z0[kChunk], z1[kChunk];
            const size_t m4 = (m + 3) & ~size_t{3};
            for (size_t j = 0; j < m; ++j) {
                if constexpr (Inside) {
                    const F4* q = line.at(i0[j]);
                    z0[j] = q[0][3];
                    z1[j] = q[1][3];
                } else {
                    z0[j] = line.depth(i0[j]);
                    z1[j] = line.depth(i1[j]);
                }
            }
            for (size_t j = m; j < m4; ++j) {
                z0[j] = z1[j] = zc;
                a0[j] = a1[j] = 0;
            }
            const F4 follow = F4{} + lp.follow, one = F4{} + 1.0f, zc4 = F4{} + zc;
            for (size_t j = 0; j < m4; j += 4) {
                F4 vz0, vz1, va0, va1;
                std::memcpy(&vz0, z0 + j, sizeof vz0);
                std::memcpy(&vz1, z1 + j, sizeof vz1);
                std::memcpy(&va0, a0 + j, sizeof va0);
                std::memcpy(&va1, a1 + j, sizeof va1);
                const F4 k0 = follow * abs4(vz0 - zc4), k1 = follow * abs4(vz1 - zc4);
                const F4 t0 = k0 < one ? k0 : one;  // NaN and inf: 1, as std::min(1, k)
                const F4 t1 = k1 < one ? k1 : one;
                const F4 vb = va0 * t0 + va1 * t1;
                va0 *= one - t0;
                va1 *= one - t1;
                std::memcpy(b + j, &vb, sizeof vb);
                std::memcpy(a0 + j, &va0, sizeof va0);
                std::memcpy(a1 + j, &va1, sizeof va1);
            }
        } else if constexpr (M == SssEdgeMode::kReject) {
            for (size_t j = 0; j < m; ++j) {
                const bool keep0 = mat[i0[j] * mstride] == mc &&
                                   std::fabs(line.depth(i0[j]) - zc) <= lp.reject_depth;
                const bool keep1 = mat[i1[j] * mstride] == mc &&
                                   std::fabs(line.depth(i1[j]) - zc) <= lp.reject_depth;
                dropped |= (!keep0 && a0[j] != 0) || (!keep1 && a1[j] != 0);
                a0[j] = keep0 ? a0[j] : 0.0f;
                a1[j] = keep1 ? a1[j] : 0.0f;
                b[j] = a0[j] + a1[j];
            }
        }
        // The weighted sums, two taps at a time.
        const F4* wt = &pt.weight[begin];
        auto tap = [&](size_t j, F4& acc, F4& extra) {
            if constexpr (Inside) {
                const F4* q = line.at(i0[j]);  // i1 = i0 + 1
                acc += wt[j] * (a0[j] * q[0] + a1[j] * q[1]);
            } else {
                acc += wt[j] * (a0[j] * line.texel(i0[j]) + a1[j] * line.texel(i1[j]));
            }
            if constexpr (M != SssEdgeMode::kNone) extra += wt[j] * b[j];
        };
        size_t j = 0;
        for (; j + 1 < m; j += 2) {
            tap(j, acc0, extra0);
            tap(j + 1, acc1, extra1);
        }
        if (j < m) tap(j, acc0, extra0);
    }
    F4 out = acc0 + acc1;
    const F4 extra = extra0 + extra1;
    if constexpr (M == SssEdgeMode::kFollowSurface) out += extra * centre;
    if constexpr (M == SssEdgeMode::kReject) {
        const F4 kept = extra;
        if (dropped)
            for (int ch = 0; ch < 3; ++ch)
                out[ch] = kept[ch] != 0
                              ? static_cast<float>(out[ch] * (pt.weight_sum[ch] / kept[ch]))
                              : static_cast<float>(pt.weight_sum[ch] * centre[ch]);
    }
    return out;
}

template <class Line>
using PixelFn = F4 (*)(const Line&, const int32_t*, ptrdiff_t, int, int, const PreparedTerm&,
                       double, const LineParams&, int, int, int);

template <SssEdgeMode M, class Line>
PixelFn<Line> pick(bool jitter, bool inside) {
    if (jitter)
        return inside ? filter_pixel<M, true, true, Line> : filter_pixel<M, true, false, Line>;
    return inside ? filter_pixel<M, false, true, Line> : filter_pixel<M, false, false, Line>;
}
template <class Line>
PixelFn<Line> pick(SssEdgeMode m, bool jitter, bool inside) {
    switch (m) {
        case SssEdgeMode::kNone:
            return pick<SssEdgeMode::kNone, Line>(jitter, inside);
        case SssEdgeMode::kFollowSurface:
            return pick<SssEdgeMode::kFollowSurface, Line>(jitter, inside);
        case SssEdgeMode::kReject:
            break;
    }
    return pick<SssEdgeMode::kReject, Line>(jitter, inside);
}

// Transparent huge pages for [p, p + bytes) where the kernel offers them on request (a hint; a
// no-op elsewhere).
void advise_huge_pages(void* p, size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    constexpr uintptr_t kHuge = uintptr_t{1} << 21;
    const uintptr_t begin = (reinterpret_cast<uintptr_t>(p) + kHuge - 1) & ~(kHuge - 1);
    const uintptr_t end = (reinterpret_cast<uintptr_t>(p) + bytes) & ~(kHuge - 1);
    if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#else
    (void)p;
    (void)bytes;
#endif
}

// The medium's bounding box [x0, x1] x [y0, y1] (x0 > x1: no medium pixel) and the rows
// [ry0, ry1] and columns [cx0, cx1] its taps can read.
struct Extent {
    int x0 = INT_MAX, x1 = INT_MIN, y0 = INT_MAX, y1 = INT_MIN;
    double sx_lo = 0, sx_hi = 0, sy_lo = 0, sy_hi = 0;  ///< extreme tap positions, pixels
    int cx0 = 0, cx1 = -1, ry0 = 0, ry1 = -1;
    size_t first_bad = SIZE_MAX;  ///< the lowest index of a bad pixel
    void join(const Extent& o) {
        x0 = std::min(x0, o.x0);
        x1 = std::max(x1, o.x1);
        y0 = std::min(y0, o.y0);
        y1 = std::max(y1, o.y1);
        sx_lo = std::min(sx_lo, o.sx_lo);
        sx_hi = std::max(sx_hi, o.sx_hi);
        sy_lo = std::min(sy_lo, o.sy_lo);
        sy_hi = std::max(sy_hi, o.sy_hi);
        first_bad = std::min(first_bad, o.first_bad);
    }
};

// The pixel checks (the first bad pixel, the lowest index whatever the thread count, is
// reported) and the extent, in one parallel scan. A tap of a term of material m at pixel pos
// lands at pos + o scale with o within reach_mm[m] and scale = per_mm_z / z, as run_line
// computes them (monotonic in o), so it reads texels within [floor(lo), floor(hi) + 1].
Extent scan_pixels(const SssGBuffer& g, const std::vector<SssMaterialKernel>& materials,
                   const std::vector<std::array<double, 2>>& reach_mm, double px_per_mm_z,
                   double py_per_mm_z) {
    const int w = g.width, h = g.height;
    Extent e = tbb::parallel_reduce(
        tbb::blocked_range<int>(0, h, 8), Extent{},
        [&](const tbb::blocked_range<int>& r, Extent acc) {
            for (int y = r.begin(); y < r.end(); ++y) {
                const size_t row = static_cast<size_t>(y) * w;
                if (row >= acc.first_bad) break;
                const int32_t* const mrow = g.material.data() + row;
                const float* const zrow = g.view_z.data() + row;
                for (int x = 0; x < w; ++x) {
                    const int32_t m = mrow[x];
                    if (m == -1) continue;
                    const float z = zrow[x];
                    if (!sss_pixel_ok(m, z, materials.size())) {
                        acc.first_bad = std::min(acc.first_bad, row + x);
                        break;
                    }
                    acc.x0 = std::min(acc.x0, x);
                    acc.x1 = std::max(acc.x1, x);
                    acc.y0 = std::min(acc.y0, y);
                    acc.y1 = std::max(acc.y1, y);
                    const std::array<double, 2>& o = reach_mm[static_cast<size_t>(m)];
                    const double sx = px_per_mm_z / z, sy = py_per_mm_z / z;
                    acc.sx_lo = std::min(acc.sx_lo, x + o[0] * sx);
                    acc.sx_hi = std::max(acc.sx_hi, x + o[1] * sx);
                    acc.sy_lo = std::min(acc.sy_lo, y + o[0] * sy);
                    acc.sy_hi = std::max(acc.sy_hi, y + o[1] * sy);
                }
            }
            return acc;
        },
        [](Extent a, const Extent& b) {
            a.join(b);
            return a;
        });
    if (e.first_bad < g.pixels()) refuse_sss_pixel(g, materials.size(), e.first_bad);
    if (e.x0 > e.x1) return e;
    // Texel indices, clamped to the image (a margin of a texel each side).
    auto index = [](double s, int len) {
        const double c = std::clamp(std::floor(s), 0.0, static_cast<double>(len - 1));
        return static_cast<int>(c);
    };
    e.cx0 = std::min(e.x0, std::max(0, index(e.sx_lo, w) - 1));
    e.cx1 = std::max(e.x1, std::min(w - 1, index(e.sx_hi, w) + 2));
    e.ry0 = std::min(e.y0, std::max(0, index(e.sy_lo, h) - 1));
    e.ry1 = std::max(e.y1, std::min(h - 1, index(e.sy_hi, h) + 2));
    return e;
}

// A scratch image of F4 texels, taken from a small process-wide pool and given back on
// destruction: kept between calls, so that a frame's pass neither page-faults nor zero-fills
// its 16 bytes a pixel (left uninitialised: every texel read is written first).
class Scratch {
  public:
    explicit Scratch(size_t n) {
        {
            const std::lock_guard<std::mutex> lock(mutex());
            auto& pool = free_list();
            for (size_t i = 0; i < pool.size(); ++i)
                if (pool[i].second >= n) {
                    buf_ = std::move(pool[i]);
                    pool.erase(pool.begin() + static_cast<ptrdiff_t>(i));
                    return;
                }
        }
        buf_.first.reset(new F4[n]);
        buf_.second = n;
        advise_huge_pages(buf_.first.get(), n * sizeof(F4));
    }
    ~Scratch() {
        const std::lock_guard<std::mutex> lock(mutex());
        auto& pool = free_list();
        pool.push_back(std::move(buf_));
        // At most two kept (concurrent calls), the largest.
        std::sort(pool.begin(), pool.end(),
                  [](const auto& a, const auto& b) { return a.second > b.second; });
        if (pool.size() > 2) pool.resize(2);
    }
    Scratch(const Scratch&) = delete;
    Scratch& operator=(const Scratch&) = delete;
    F4* data() { return buf_.first.get(); }

  private:
    using Buffer = std::pair<std::unique_ptr<F4[]>, size_t>;
    static std::mutex& mutex() {
        static std::mutex m;
        return m;
    }
    static std::vector<Buffer>& free_list() {
        static std::vector<Buffer> pool;
        return pool;
    }
    Buffer buf_;
};

// ---- Rotated axes [JimenezSupp Figs. S.6, S.7] ------------------------------------------------

// The angle of a pixel's first pass axis, in [0, pi): a hash of the pixel and the seed (pass
// index -1, which the jitter does not use). Not [0, pi / 2), although the pair of axes repeats
// with that period: the two passes are not interchangeable (the second reads the neighbours'
// first), and each must take every direction for the mean over angles to be isotropic.
double rotation_angle(int x, int y, uint32_t seed) {
    return std::numbers::pi / 2 * (approx::jitter_hash(x, y, -1, -1, seed) + 1);
}

// One output pixel of a 1D pass of term pt along the axis (ax, ay) pixels per mm at pixel
// (x, y) of a w x h row-major image of R, G, B, z texels: each tap at o mm is sampled at
// (x + o ax, y + o ay) bilinearly from its four texels (approx::tap_texels's rule along each
// axis, so clamp-to-edge), and the edge rule of sss_pass.h is applied to each of the four with
// its own depth and material and weight (1 - t_x)(1 - t_y), t_x (1 - t_y), (1 - t_x) t_y or
// t_x t_y.
template <SssEdgeMode M>
F4 filter_pixel_2d(const F4* src, const int32_t* mat, int w, int h, int x, int y, double ax,
                   double ay, const PreparedTerm& pt, const LineParams& lp, bool jitter, int pass) {
    const approx::TapKernel& taps = pt.term->taps;
    const size_t ci = static_cast<size_t>(y) * w + x;
    const F4 centre = src[ci];
    const float zc = centre[3];
    const int32_t mc = mat[ci];
    F4 acc{}, extra{};  // extra: follow's centre weight, reject's kept weight
    bool dropped = false;
    for (size_t i = 0; i < taps.offset_mm.size(); ++i) {
        double o = taps.offset_mm[i];
        if (jitter)
            o = approx::jittered_offset_mm(
                taps, pt.range, i, approx::jitter_hash(x, y, pass, static_cast<int>(i), lp.seed));
        const approx::TapTexels tx = approx::tap_texels(x + o * ax, w);
        const approx::TapTexels ty = approx::tap_texels(y + o * ay, h);
        const float fx = static_cast<float>(tx.t), fy = static_cast<float>(ty.t);
        const size_t r0 = static_cast<size_t>(ty.i0) * w, r1 = static_cast<size_t>(ty.i1) * w;
        const size_t q[4] = {r0 + tx.i0, r0 + tx.i1, r1 + tx.i0, r1 + tx.i1};
        const float a[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
        F4 sum{};
        float b = 0;
        for (int c = 0; c < 4; ++c) {
            float wc = a[c];
            const F4 v = src[q[c]];
            if constexpr (M == SssEdgeMode::kFollowSurface) {
                // [Freude14 Eq. 4.12] per texel: v (1 - s) + centre s.
                const float k = lp.follow * std::fabs(v[3] - zc);
                const float sv = k < 1.0f ? k : 1.0f;  // NaN and inf: 1
                b += wc * sv;
                wc *= 1 - sv;
            } else if constexpr (M == SssEdgeMode::kReject) {
                const bool keep = mat[q[c]] == mc && std::fabs(v[3] - zc) <= lp.reject_depth;
                dropped |= !keep && wc != 0;
                wc = keep ? wc : 0.0f;
                b += wc;
            }
            sum += wc * v;
        }
        acc += pt.weight[i] * sum;
        if constexpr (M != SssEdgeMode::kNone) extra += pt.weight[i] * b;
    }
    F4 out = acc;
    if constexpr (M == SssEdgeMode::kFollowSurface) out += extra * centre;
    if constexpr (M == SssEdgeMode::kReject) {
        if (dropped)
            for (int ch = 0; ch < 3; ++ch)
                out[ch] = extra[ch] != 0
                              ? static_cast<float>(out[ch] * (pt.weight_sum[ch] / extra[ch]))
                              : static_cast<float>(pt.weight_sum[ch] * centre[ch]);
    }
    return out;
}

using Pixel2DFn = F4 (*)(const F4*, const int32_t*, int, int, int, int, double, double,
                         const PreparedTerm&, const LineParams&, bool, int);

// The pass with rotated axes (SssParams::rotate): per term, the first 1D pass along each
// pixel's (cos a, sin a), the second along its (-sin a, cos a), on the plane of the medium in
// mm, so in pixels (cos a px, sin a py) and (-sin a px, cos a py) per mm with px, py the
// horizontal and vertical scales of Eq. 4.11 at the centre's depth. Rows in parallel, each
// pixel on its own: bit-identical for any thread count.
void rotated_pass(const SssGBuffer& g, const std::vector<std::vector<PreparedTerm>>& prep,
                  size_t rank, const SssParams& p, const LineParams& lp, double px_per_mm_z,
                  double py_per_mm_z, std::vector<float>& out) {
    const int w = g.width, h = g.height;
    const size_t n = g.pixels();
    const bool jitter = p.jitter > 0;
    Pixel2DFn fn = filter_pixel_2d<SssEdgeMode::kReject>;
    if (p.mode == SssEdgeMode::kNone) fn = filter_pixel_2d<SssEdgeMode::kNone>;
    if (p.mode == SssEdgeMode::kFollowSurface) fn = filter_pixel_2d<SssEdgeMode::kFollowSurface>;
    Scratch in_s(n), tmp_s(n);
    F4* const in = in_s.data();
    F4* const tmp = tmp_s.data();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 16384),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t i = r.begin(); i < r.end(); ++i) {
                              const float* e = &g.irradiance[3 * i];
                              in[i] = F4{e[0], e[1], e[2], g.view_z[i]};
                          }
                      });
    const int32_t* mat = g.material.data();
    // The pass of term k along axis dir (0: the first, 1: the second) at pixel (x, y), from src;
    // false where the pixel has no term k.
    auto pixel = [&](const F4* src, int x, int y, size_t k, int dir, F4& v) {
        const size_t i = static_cast<size_t>(y) * w + x;
        const int32_t m = mat[i];
        if (m < 0 || k >= prep[static_cast<size_t>(m)].size()) return false;
        const PreparedTerm& pt = prep[static_cast<size_t>(m)][k];
        const F4 c = src[i];
        const double a = rotation_angle(x, y, p.seed);
        const double ca = std::cos(a), sa = std::sin(a);
        const double px = px_per_mm_z / c[3], py = py_per_mm_z / c[3];
        const double ax = dir == 0 ? ca * px : -sa * px, ay = dir == 0 ? sa * py : ca * py;
        if (pt.term->taps.support_mm * std::max(std::fabs(ax), std::fabs(ay)) < 0.5) {
            // Every tap within the centre pixel's bin: the identity times the mass.
            v = F4{};
            for (int ch = 0; ch < 3; ++ch) v[ch] = static_cast<float>(pt.weight_sum[ch] * c[ch]);
            return true;
        }
        v = fn(src, mat, w, h, x, y, ax, ay, pt, lp, jitter, static_cast<int>(2 * k) + dir);
        return true;
    };
    for (size_t k = 0; k < rank; ++k) {
        tbb::parallel_for(tbb::blocked_range<int>(0, h, 4), [&](const tbb::blocked_range<int>& r) {
            for (int y = r.begin(); y < r.end(); ++y)
                for (int x = 0; x < w; ++x) {
                    const size_t i = static_cast<size_t>(y) * w + x;
                    F4 v;
                    if (!pixel(in, x, y, k, 0, v)) v = in[i];  // held between the passes
                    v[3] = in[i][3];
                    tmp[i] = v;
                }
        });
        tbb::parallel_for(tbb::blocked_range<int>(0, h, 4), [&](const tbb::blocked_range<int>& r) {
            for (int y = r.begin(); y < r.end(); ++y)
                for (int x = 0; x < w; ++x) {
                    const size_t i = static_cast<size_t>(y) * w + x;
                    const int32_t m = mat[i];
                    if (m < 0) continue;  // passes its input through
                    F4 v;
                    if (!pixel(tmp, x, y, k, 1, v)) {
                        if (k == 0)
                            for (int ch = 0; ch < 3; ++ch) out[3 * i + ch] = 0;
                        continue;
                    }
                    const SssTerm& t = *prep[static_cast<size_t>(m)][k].term;
                    for (int ch = 0; ch < 3; ++ch) {
                        const float sv = static_cast<float>(t.sign[ch]) * v[ch];
                        out[3 * i + ch] = k == 0 ? sv : out[3 * i + ch] + sv;
                    }
                }
        });
    }
}

// Term t's taps prepared for the pass, with jitter amplitude `jitter`.
PreparedTerm prepare_term(const SssTerm& t, double jitter) {
    const bool jittered = jitter > 0;
    PreparedTerm pt;
    pt.term = &t;
    pt.range = approx::tap_jitter_range(t.taps, jitter);
    const size_t count = t.taps.offset_mm.size();
    pt.weight.assign(count, F4{});
    pt.lo_mm = pt.hi_mm = t.taps.offset_mm[0];
    for (size_t i = 0; i < count; ++i) {
        for (int ch = 0; ch < 3; ++ch) {
            pt.weight_sum[ch] += t.taps.weight[ch][i];
            pt.weight[i][ch] = static_cast<float>(t.taps.weight[ch][i]);
        }
        pt.weight[i][3] = 0;
        // The positions a tap reaches: jittered_offset_mm is monotonic in xi.
        const double lo =
            jittered ? approx::jittered_offset_mm(t.taps, pt.range, i, -1.0) : t.taps.offset_mm[i];
        const double hi =
            jittered ? approx::jittered_offset_mm(t.taps, pt.range, i, 1.0) : t.taps.offset_mm[i];
        pt.lo_mm = std::min(pt.lo_mm, lo);
        pt.hi_mm = std::max(pt.hi_mm, hi);
    }
    return pt;
}

// Every material's prepared terms, the extreme offsets [mm] their taps reach, and the largest
// number of terms.
struct PreparedMaterials {
    std::vector<std::vector<PreparedTerm>> prep;
    std::vector<std::array<double, 2>> reach_mm;
    size_t rank = 0;
};

PreparedMaterials prepare_materials(const std::vector<SssMaterialKernel>& materials,
                                    const SssParams& p) {
    PreparedMaterials pm;
    pm.prep.resize(materials.size());
    pm.reach_mm.assign(materials.size(), {0.0, 0.0});
    for (size_t m = 0; m < materials.size(); ++m) {
        pm.rank = std::max(pm.rank, materials[m].terms.size());
        for (const SssTerm& t : materials[m].terms) {
            PreparedTerm pt = prepare_term(t, p.jitter);
            pm.reach_mm[m][0] = std::min(pm.reach_mm[m][0], pt.lo_mm);
            pm.reach_mm[m][1] = std::max(pm.reach_mm[m][1], pt.hi_mm);
            pm.prep[m].push_back(std::move(pt));
        }
    }
    return pm;
}

// The output starts as the input (what material -1 keeps), copied in parallel blocks.
void copy_input(const SssGBuffer& g, std::vector<float>& out) {
    out.resize(g.irradiance.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, g.irradiance.size(), size_t{1} << 16),
                      [&](const tbb::blocked_range<size_t>& r) {
                          std::copy(g.irradiance.begin() + static_cast<ptrdiff_t>(r.begin()),
                                    g.irradiance.begin() + static_cast<ptrdiff_t>(r.end()),
                                    out.begin() + static_cast<ptrdiff_t>(r.begin()));
                      });
}

// The fast path's pairs (unclamped, unjittered, follow-surface or none).
using PairFn = void (*)(const F4*, int, double, const F4*, int, double, const double*, const F4*,
                        size_t, float, F4*);

// The pass along the image's axes, per term: horizontal, then vertical.
//
// The horizontal pass reads a row of R, G, B, z texels (built per row, so it stays in cache)
// and writes its result transposed (column-major), so that the vertical pass reads contiguous
// memory too: columns x0..x1 of the box, rows ry0..ry1 (hr of them). The scratch image is kept
// between calls (no page faults, no zero fill).
class SeparablePass {
  public:
    SeparablePass(const SssGBuffer& g, const std::vector<std::vector<PreparedTerm>>& prep,
                  const SssParams& p, const LineParams& lp, const Extent& ext, double px_per_mm_z,
                  double py_per_mm_z, std::vector<float>& out)
        : g_(g),
          prep_(prep),
          lp_(lp),
          ext_(ext),
          px_per_mm_z_(px_per_mm_z),
          py_per_mm_z_(py_per_mm_z),
          out_(out),
          column_fn_{pick<ColumnLine>(p.mode, p.jitter > 0, false),
                     pick<ColumnLine>(p.mode, p.jitter > 0, true)},
          pair_fn_(p.jitter > 0 || p.mode == SssEdgeMode::kReject ? nullptr
                   : p.mode == SssEdgeMode::kFollowSurface        ? fast_pair_follow
                                                                  : fast_pair_none),
          bw_(ext.x1 - ext.x0 + 1),
          hr_(ext.ry1 - ext.ry0 + 1),
          tmp_s_(static_cast<size_t>(bw_) * hr_),
          tmp_(tmp_s_.data()),
          blocks_((hr_ + kBlock - 1) / kBlock),
          busy_(static_cast<size_t>(blocks_) * bw_, 0) {}

    // Every term, summed into the output.
    void run(size_t rank) {
        for (size_t k = 0; k < rank; ++k) {
            horizontal(k);
            vertical(k);
        }
    }

  private:
    // Blocks of kBlock rows from ry0: the horizontal pass writes each column of a block as
    // kBlock contiguous texels, and notes which block columns hold a medium pixel (busy), so
    // that the vertical pass skips the rest (it would store nothing there).
    static constexpr int kBlock = 16;
    static constexpr int kGrain = 16;

    // One 1D pass of term k at positions [begin, end) of a line of len texels, materials at
    // mat[pos * mstride]: calls store(pos, value) for the medium pixels whose kernel has term k,
    // store(pos, nullptr) for the others.
    template <class Store>
    void run_line(const ColumnLine& line, const int32_t* mat, ptrdiff_t mstride, int len, int begin,
                  int end, size_t k, int dir, int index, double per_mm_z, Store&& store) const {
        for (int pos = begin; pos < end; ++pos) {
            const int32_t m = mat[pos * mstride];
            if (m < 0 || k >= prep_[static_cast<size_t>(m)].size()) {
                store(pos, nullptr);
                continue;
            }
            const PreparedTerm& pt = prep_[static_cast<size_t>(m)][k];
            const F4 c = line.texel(pos);
            const double scale = per_mm_z / c[3];
            if (pt.term->taps.support_mm * scale < 0.5) {
                // The whole kernel within the centre pixel's bin: the identity times the
                // kernel's mass (approx/convolve.h's convention).
                F4 v{};
                for (int ch = 0; ch < 3; ++ch)
                    v[ch] = static_cast<float>(pt.weight_sum[ch] * c[ch]);
                store(pos, &v);
                continue;
            }
            const bool inside = pos + pt.lo_mm * scale >= 0 && pos + pt.hi_mm * scale < len - 1;
            if (pair_fn_ && inside && pos + 1 < end && mat[(pos + 1) * mstride] == m) {
                // The next pixel on the fast path too: both at once.
                const F4 c1 = line.texel(pos + 1);
                const double scale1 = per_mm_z / c1[3];
                if (!(pt.term->taps.support_mm * scale1 < 0.5) &&
                    pos + 1 + pt.lo_mm * scale1 >= 0 && pos + 1 + pt.hi_mm * scale1 < len - 1) {
                    F4 v2[2];
                    pair_fn_(line.at(pos), pos, scale, line.at(pos + 1), pos + 1, scale1,
                             pt.term->taps.offset_mm.data(), pt.weight.data(),
                             pt.term->taps.offset_mm.size(), lp_.follow, v2);
                    store(pos, &v2[0]);
                    store(pos + 1, &v2[1]);
                    ++pos;
                    continue;
                }
            }
            const int x = dir == 0 ? pos : index, y = dir == 0 ? index : pos;
            const F4 v = column_fn_[inside](line, mat, mstride, len, pos, pt, scale, lp_, x, y,
                                            static_cast<int>(2 * k) + dir);
            store(pos, &v);
        }
    }

    // Horizontal, written transposed: pixels without term k hold their input.
    void horizontal(size_t k) {
        tbb::parallel_for(tbb::blocked_range<int>(0, blocks_, 1),
                          [&](const tbb::blocked_range<int>& r) {
                              const int w = g_.width;
                              thread_local std::vector<F4> buf_tl, block_tl;
                              if (buf_tl.size() < static_cast<size_t>(w))
                                  buf_tl.resize(static_cast<size_t>(w));
                              if (block_tl.size() < static_cast<size_t>(bw_) * kBlock)
                                  block_tl.resize(static_cast<size_t>(bw_) * kBlock);
                              for (int b = r.begin(); b < r.end(); ++b)
                                  horizontal_block(k, b, buf_tl.data(), block_tl.data());
                          });
    }

    // Block b of the horizontal pass of term k, through the row buffer buf and the block
    // buffer block (bw x kBlock texels), into the transposed image.
    void horizontal_block(size_t k, int b, F4* const buf, F4* const block) {
        const int w = g_.width;
        const int y0 = ext_.ry0 + b * kBlock, y1 = std::min(ext_.ry1 + 1, y0 + kBlock);
        for (int y = y0; y < y1; ++y) {
            const size_t row = static_cast<size_t>(y) * w;
            // Local pointers: the byte stores below may alias anything, which would reload the
            // vectors' pointers every pixel and keep GCC from vectorising.
            const float* const irr = g_.irradiance.data() + 3 * row;
            const float* const vz = g_.view_z.data() + row;
            const int32_t* const mrow = g_.material.data() + row;
            for (int x = ext_.cx0; x <= ext_.cx1; ++x)
                buf[x] = F4{irr[3 * x], irr[3 * x + 1], irr[3 * x + 2], vz[x]};
            if (k == 0) {
                uint8_t* const bz = busy_.data() + static_cast<size_t>(b) * bw_;
                const int32_t* const mb = mrow + ext_.x0;
                for (int x = 0; x < bw_; ++x)
                    bz[x] = static_cast<uint8_t>(bz[x] | (mb[x] >= 0 ? 1 : 0));
            }
            const ColumnLine line{buf};
            const int x0 = ext_.x0;
            run_line(line, &g_.material[row], 1, w, ext_.x0, ext_.x1 + 1, k, 0, y, px_per_mm_z_,
                     [&](int x, const F4* v) {
                         F4& dst = block[static_cast<size_t>(x - x0) * kBlock + (y - y0)];
                         const F4 src = buf[x];
                         dst = v ? *v : src;
                         dst[3] = src[3];
                     });
        }
        for (int x = 0; x < bw_; ++x)
            std::memcpy(&tmp_[static_cast<size_t>(x) * hr_ + (y0 - ext_.ry0)],
                        &block[static_cast<size_t>(x) * kBlock],
                        static_cast<size_t>(y1 - y0) * sizeof(F4));
    }

    // Vertical, over the columns, summed with the term's signs into the output (term 0 sets
    // it: a material without terms gives 0, as an empty sum).
    void vertical(size_t k) {
        tbb::parallel_for(tbb::blocked_range<int>(0, bw_, kGrain),
                          [&](const tbb::blocked_range<int>& r) {
                              for (int xb = r.begin(); xb < r.end(); ++xb) vertical_column(k, xb);
                          });
    }

    // Column xb of the box in the vertical pass of term k.
    void vertical_column(size_t k, int xb) {
        const int w = g_.width, h = g_.height;
        const int x = ext_.x0 + xb;
        const ColumnLine line{&tmp_[static_cast<size_t>(xb) * hr_], ext_.ry0};
        // The taps reach far along the column, in no order a hardware prefetcher follows: the
        // next column is fetched while this one is filtered.
        if (xb + 1 < bw_) {
            const char* next =
                reinterpret_cast<const char*>(&tmp_[static_cast<size_t>(xb + 1) * hr_]);
            for (size_t o = 0; o < static_cast<size_t>(hr_) * sizeof(F4); o += 64)
                __builtin_prefetch(next + o);
        }
        std::vector<float>& out = out_;
        for (int b = 0; b < blocks_; ++b) {
            if (!busy_[static_cast<size_t>(b) * bw_ + xb]) continue;
            const int y0 = ext_.ry0 + b * kBlock;
            run_line(line, &g_.material[static_cast<size_t>(x)], w, h, y0,
                     std::min(ext_.ry1 + 1, y0 + kBlock), k, 1, x, py_per_mm_z_,
                     [&](int y, const F4* v) {
                         const size_t c = static_cast<size_t>(y) * w + x;
                         const int32_t m = g_.material[c];
                         if (!v) {
                             if (k == 0 && m >= 0)
                                 for (int ch = 0; ch < 3; ++ch) out[3 * c + ch] = 0;
                             return;
                         }
                         const SssTerm& t = *prep_[static_cast<size_t>(m)][k].term;
                         for (int ch = 0; ch < 3; ++ch) {
                             const float sv = static_cast<float>(t.sign[ch]) * (*v)[ch];
                             out[3 * c + ch] = k == 0 ? sv : out[3 * c + ch] + sv;
                         }
                     });
        }
    }

    const SssGBuffer& g_;
    const std::vector<std::vector<PreparedTerm>>& prep_;
    const LineParams& lp_;
    const Extent& ext_;
    const double px_per_mm_z_, py_per_mm_z_;
    std::vector<float>& out_;
    const PixelFn<ColumnLine> column_fn_[2];
    const PairFn pair_fn_;
    const int bw_, hr_;
    Scratch tmp_s_;
    F4* const tmp_;
    const int blocks_;
    std::vector<uint8_t> busy_;
};

}  // namespace

std::vector<float> sss_pass(const SssGBuffer& g, const std::vector<SssMaterialKernel>& materials,
                            const SssParams& p) {
    std::vector<float> out;
    sss_pass(g, materials, p, out);
    return out;
}

void sss_pass(const SssGBuffer& g, const std::vector<SssMaterialKernel>& materials,
              const SssParams& p, std::vector<float>& out) {
    check_sss_inputs(g, materials, p);
    const int w = g.width, h = g.height;
    const PreparedMaterials pm = prepare_materials(materials, p);
    LineParams lp;
    lp.follow = static_cast<float>(p.follow_strength / p.tan_half);
    lp.reject_depth = static_cast<float>(p.reject_depth);
    lp.seed = p.seed;

    // Kernel scale [Freude14 Eq. 4.11]: pixels per mm at view depth z, along y and along x.
    const double py_per_mm_z = h / (2.0 * p.tan_half * p.unit_mm);
    const double px_per_mm_z = w / (2.0 * p.tan_half * p.aspect * p.unit_mm);

    // The pixels checked, and the region the pass touches: the medium's bounding box, and the
    // rows and columns its taps can read (the horizontal pass runs on those rows only, and the
    // vertical pass reads nothing else).
    const Extent ext = scan_pixels(g, materials, pm.reach_mm, px_per_mm_z, py_per_mm_z);

    copy_input(g, out);
    if (ext.x0 > ext.x1) return;  // no medium pixel
    if (p.rotate) {
        rotated_pass(g, pm.prep, pm.rank, p, lp, px_per_mm_z, py_per_mm_z, out);
        return;
    }
    SeparablePass(g, pm.prep, p, lp, ext, px_per_mm_z, py_per_mm_z, out).run(pm.rank);
}

}  // namespace ssslab::realtime
