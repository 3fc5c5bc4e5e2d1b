#include "realtime/sss_pass.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

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

namespace {

void check(const SssGBuffer& g, const std::vector<SssMaterialKernel>& materials,
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
    for (size_t i = 0; i < n; ++i) {
        const int32_t m = g.material[i];
        if (m < -1 || m >= static_cast<int32_t>(materials.size()))
            throw std::invalid_argument("sss_pass: material index " + std::to_string(m) +
                                        " without a kernel");
        if (m >= 0 && !(g.view_z[i] > 0 && std::isfinite(g.view_z[i])))
            throw std::invalid_argument("sss_pass: a medium pixel has no positive finite depth");
    }
}

// A texel of a pass's input: R, G, B and the view z in the fourth lane, so that one 16-byte
// load fetches everything a tap needs (GCC vector extension: SSE2 on any x86-64).
typedef float F4 __attribute__((vector_size(16)));

// One term's taps prepared for the pass.
struct PreparedTerm {
    const SssTerm* term = nullptr;
    approx::TapJitterRange range;
    std::array<double, 3> weight_sum{};
    F4 weight_sum4{};             ///< weight_sum as floats, lane 3 zero
    std::vector<F4> weight;       ///< per tap (R, G, B, 0) as floats
    double lo_mm = 0, hi_mm = 0;  ///< the extreme offsets a tap can reach (with jitter)
};

// What one 1D pass needs besides the line it reads.
struct LineParams {
    float follow = 0;        ///< follow_strength / tan_half
    float reject_depth = 0;  ///< kReject's largest depth difference
    double jitter = 0;
    uint32_t seed = 0;
};

// One output pixel of a 1D pass of term pt at position pos of a line (a row, or a column of the
// transposed image) of len texels: the rules of the file comment of sss_pass.h, per texel.
// `line` holds R, G, B, z per texel, `mat` the materials along the line; (x, y, pass) feed the
// jitter hash. Inside: every tap position lies within [0, len - 1), so no clamping is needed.
template <SssEdgeMode M, bool Jitter, bool Inside>
F4 filter_pixel(const F4* line, const int32_t* mat, int len, int pos, const PreparedTerm& pt,
                double scale, const LineParams& lp, int x, int y, int pass) {
    const approx::TapKernel& taps = pt.term->taps;
    const F4 centre = line[pos];
    const float zc = centre[3];
    const int32_t mc = mat[pos];
    F4 acc{}, extra{};  // extra: follow-surface's weight of the centre, rejection's kept weight
    bool dropped = false;
    const size_t count = taps.offset_mm.size();
    auto texel = [&](int q, float tw, F4 w) {
        const F4 v = line[q];
        if constexpr (M == SssEdgeMode::kNone) {
            acc += (w * tw) * v;
        } else if constexpr (M == SssEdgeMode::kFollowSurface) {
            // [Freude14 Eq. 4.12]: s_c = o_c (1 - t) + i_c t, the centre's share summed apart.
            const float kd = lp.follow * std::fabs(v[3] - zc);
            const float t = kd < 1.0f ? kd : 1.0f;  // NaN and inf: 1, as std::min(1, kd)
            acc += (w * (tw * (1 - t))) * v;
            extra += w * (tw * t);
        } else {
            const float dz = std::fabs(v[3] - zc);
            const bool keep = mat[q] == mc && dz <= lp.reject_depth;
            dropped |= !keep && tw != 0;
            const F4 wk = w * (keep ? tw : 0.0f);
            acc += wk * v;
            extra += wk;
        }
    };
    for (size_t i = 0; i < count; ++i) {
        double o = taps.offset_mm[i];
        if constexpr (Jitter)
            o = approx::jittered_offset_mm(
                taps, pt.range, i, approx::jitter_hash(x, y, pass, static_cast<int>(i), lp.seed));
        const double s = pos + o * scale;
        int i0, i1;
        double t;
        if constexpr (Inside) {
            i0 = static_cast<int>(s);
            i1 = i0 + 1;
            t = s - i0;
        } else {
            const approx::TapTexels tt = approx::tap_texels(s, len);
            i0 = tt.i0;
            i1 = tt.i1;
            t = tt.t;
        }
        const float tf = static_cast<float>(t);
        texel(i0, 1 - tf, pt.weight[i]);
        texel(i1, tf, pt.weight[i]);
    }
    F4 out = acc;
    if constexpr (M == SssEdgeMode::kFollowSurface) out += extra * centre;
    if constexpr (M == SssEdgeMode::kReject) {
        if (dropped)
            for (int ch = 0; ch < 3; ++ch)
                out[ch] = extra[ch] != 0
                              ? static_cast<float>(acc[ch] * (pt.weight_sum[ch] / extra[ch]))
                              : static_cast<float>(pt.weight_sum[ch] * centre[ch]);
    }
    return out;
}

using PixelFn = F4 (*)(const F4*, const int32_t*, int, int, const PreparedTerm&, double,
                       const LineParams&, int, int, int);

template <SssEdgeMode M>
PixelFn pick(bool jitter, bool inside) {
    if (jitter) return inside ? filter_pixel<M, true, true> : filter_pixel<M, true, false>;
    return inside ? filter_pixel<M, false, true> : filter_pixel<M, false, false>;
}
PixelFn pick(SssEdgeMode m, bool jitter, bool inside) {
    switch (m) {
        case SssEdgeMode::kNone:
            return pick<SssEdgeMode::kNone>(jitter, inside);
        case SssEdgeMode::kFollowSurface:
            return pick<SssEdgeMode::kFollowSurface>(jitter, inside);
        case SssEdgeMode::kReject:
            break;
    }
    return pick<SssEdgeMode::kReject>(jitter, inside);
}

}  // namespace

std::vector<float> sss_pass(const SssGBuffer& g, const std::vector<SssMaterialKernel>& materials,
                            const SssParams& p) {
    check(g, materials, p);
    const int w = g.width, h = g.height;
    const size_t n = g.pixels();
    const bool jitter = p.jitter > 0;

    std::vector<std::vector<PreparedTerm>> prep(materials.size());
    size_t rank = 0;
    for (size_t m = 0; m < materials.size(); ++m) {
        rank = std::max(rank, materials[m].terms.size());
        for (const SssTerm& t : materials[m].terms) {
            PreparedTerm pt;
            pt.term = &t;
            pt.range = approx::tap_jitter_range(t.taps, p.jitter);
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
                const double lo = jitter ? approx::jittered_offset_mm(t.taps, pt.range, i, -1.0)
                                         : t.taps.offset_mm[i];
                const double hi = jitter ? approx::jittered_offset_mm(t.taps, pt.range, i, 1.0)
                                         : t.taps.offset_mm[i];
                pt.lo_mm = std::min(pt.lo_mm, lo);
                pt.hi_mm = std::max(pt.hi_mm, hi);
            }
            for (int ch = 0; ch < 3; ++ch)
                pt.weight_sum4[ch] = static_cast<float>(pt.weight_sum[ch]);
            prep[m].push_back(std::move(pt));
        }
    }
    LineParams lp;
    lp.follow = static_cast<float>(p.follow_strength / p.tan_half);
    lp.reject_depth = static_cast<float>(p.reject_depth);
    lp.jitter = p.jitter;
    lp.seed = p.seed;
    PixelFn fn[2] = {pick(p.mode, jitter, false), pick(p.mode, jitter, true)};

    // Kernel scale [Freude14 Eq. 4.11]: pixels per mm at view depth z, along y and along x.
    const double py_per_mm_z = h / (2.0 * p.tan_half * p.unit_mm);
    const double px_per_mm_z = w / (2.0 * p.tan_half * p.aspect * p.unit_mm);

    // The input as R, G, B, z texels, row-major; the horizontal pass writes its result
    // transposed (column-major), so that the vertical pass reads contiguous memory too.
    std::vector<F4> in(n, F4{}), tmp(n, F4{});
    std::vector<int32_t> mat_t(n);
    std::vector<float> out(3 * n);
    const int grain = 16;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t c = r.begin(); c < r.end(); ++c) {
                              const float* e = &g.irradiance[3 * c];
                              in[c] = F4{e[0], e[1], e[2], g.view_z[c]};
                              const bool medium = g.material[c] >= 0;
                              for (int ch = 0; ch < 3; ++ch) out[3 * c + ch] = medium ? 0 : e[ch];
                          }
                      });
    tbb::parallel_for(tbb::blocked_range<int>(0, w, grain), [&](const tbb::blocked_range<int>& r) {
        for (int x = r.begin(); x < r.end(); ++x)
            for (int y = 0; y < h; ++y)
                mat_t[static_cast<size_t>(x) * h + y] = g.material[static_cast<size_t>(y) * w + x];
    });

    // One 1D pass of term k over line `line` (0..lines-1) of src: calls store(pos, value) for
    // the medium pixels whose kernel has term k, store(pos, nullptr) for the others.
    auto run_line = [&](const F4* src, const int32_t* mat, int len, size_t k, int dir, int line,
                        double per_mm_z, auto&& store) {
        for (int pos = 0; pos < len; ++pos) {
            const int32_t m = mat[pos];
            if (m < 0 || k >= prep[static_cast<size_t>(m)].size()) {
                store(pos, nullptr);
                continue;
            }
            const PreparedTerm& pt = prep[static_cast<size_t>(m)][k];
            const double scale = per_mm_z / src[pos][3];
            if (pt.term->taps.support_mm * scale < 0.5) {
                // The whole kernel within the centre pixel's bin: the identity times the
                // kernel's mass (approx/convolve.h's convention).
                F4 v;
                for (int ch = 0; ch < 3; ++ch)
                    v[ch] = static_cast<float>(pt.weight_sum[ch] * src[pos][ch]);
                v[3] = 0;
                store(pos, &v);
                continue;
            }
            const bool inside = pos + pt.lo_mm * scale >= 0 && pos + pt.hi_mm * scale < len - 1;
            const int x = dir == 0 ? pos : line, y = dir == 0 ? line : pos;
            const F4 v =
                fn[inside](src, mat, len, pos, pt, scale, lp, x, y, static_cast<int>(2 * k) + dir);
            store(pos, &v);
        }
    };

    for (size_t k = 0; k < rank; ++k) {
        // Horizontal, written transposed: pixels without term k hold their input.
        tbb::parallel_for(tbb::blocked_range<int>(0, h, grain),
                          [&](const tbb::blocked_range<int>& r) {
                              for (int y = r.begin(); y < r.end(); ++y) {
                                  const size_t row = static_cast<size_t>(y) * w;
                                  run_line(&in[row], &g.material[row], w, k, 0, y, px_per_mm_z,
                                           [&](int x, const F4* v) {
                                               F4& dst = tmp[static_cast<size_t>(x) * h + y];
                                               const F4 src = in[row + x];
                                               dst = v ? *v : src;
                                               dst[3] = src[3];
                                           });
                              }
                          });
        // Vertical, over the columns, summed with the term's signs.
        tbb::parallel_for(
            tbb::blocked_range<int>(0, w, grain), [&](const tbb::blocked_range<int>& r) {
                for (int x = r.begin(); x < r.end(); ++x) {
                    const size_t col = static_cast<size_t>(x) * h;
                    run_line(
                        &tmp[col], &mat_t[col], h, k, 1, x, py_per_mm_z, [&](int y, const F4* v) {
                            if (!v) return;
                            const size_t c = static_cast<size_t>(y) * w + x;
                            const SssTerm& t = *prep[static_cast<size_t>(g.material[c])][k].term;
                            for (int ch = 0; ch < 3; ++ch)
                                out[3 * c + ch] += static_cast<float>(t.sign[ch]) * (*v)[ch];
                        });
                }
            });
    }
    return out;
}

}  // namespace ssslab::realtime
