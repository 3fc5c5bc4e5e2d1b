#include "realtime/sss_pass.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

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

// One term's taps prepared for the pass.
struct PreparedTerm {
    const SssTerm* term = nullptr;
    approx::TapJitterRange range;
    std::array<double, 3> weight_sum{};
};

}  // namespace

std::vector<float> sss_pass(const SssGBuffer& g, const std::vector<SssMaterialKernel>& materials,
                            const SssParams& p) {
    check(g, materials, p);
    const int w = g.width, h = g.height;
    const size_t n = g.pixels();

    std::vector<std::vector<PreparedTerm>> prep(materials.size());
    size_t rank = 0;
    for (size_t m = 0; m < materials.size(); ++m) {
        rank = std::max(rank, materials[m].terms.size());
        for (const SssTerm& t : materials[m].terms) {
            PreparedTerm pt;
            pt.term = &t;
            pt.range = approx::tap_jitter_range(t.taps, p.jitter);
            for (int ch = 0; ch < 3; ++ch)
                for (double v : t.taps.weight[ch]) pt.weight_sum[ch] += v;
            prep[m].push_back(std::move(pt));
        }
    }

    // Kernel scale [Freude14 Eq. 4.11]: pixels per mm at view depth z, along y and along x.
    const double py_per_mm_z = h / (2.0 * p.tan_half * p.unit_mm);
    const double px_per_mm_z = w / (2.0 * p.tan_half * p.aspect * p.unit_mm);

    std::vector<double> in(3 * n), tmp(3 * n), acc(3 * n, 0.0);
    for (size_t i = 0; i < 3 * n; ++i) in[i] = g.irradiance[i];

    // One 1D pass of term k along dir (0: x, 1: y) over src: store(c, value) for the medium
    // pixels whose kernel has term k, store(c, nullptr) for the others.
    auto pass = [&](const std::vector<double>& src, size_t k, int dir, auto&& store) {
        const int len = dir == 0 ? w : h;
        tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
            for (int y = rows.begin(); y < rows.end(); ++y)
                for (int x = 0; x < w; ++x) {
                    const size_t c = static_cast<size_t>(y) * w + static_cast<size_t>(x);
                    const int32_t mat = g.material[c];
                    if (mat < 0 || k >= prep[static_cast<size_t>(mat)].size()) {
                        store(c, nullptr);
                        continue;
                    }
                    const PreparedTerm& pt = prep[static_cast<size_t>(mat)][k];
                    const approx::TapKernel& taps = pt.term->taps;
                    const double zc = g.view_z[c];
                    const double scale = (dir == 0 ? px_per_mm_z : py_per_mm_z) / zc;
                    std::array<double, 3> out{};
                    const double* centre = &src[3 * c];
                    if (taps.support_mm * scale < 0.5) {
                        // The whole kernel within the centre pixel's bin: the identity times
                        // the kernel's mass (approx/convolve.h's convention).
                        for (int ch = 0; ch < 3; ++ch) out[ch] = pt.weight_sum[ch] * centre[ch];
                        store(c, out.data());
                        continue;
                    }
                    const int pos = dir == 0 ? x : y;
                    std::array<double, 3> kept{};
                    bool dropped = false;
                    const size_t count = taps.offset_mm.size();
                    for (size_t i = 0; i < count; ++i) {
                        const double xi =
                            p.jitter > 0 ? approx::jitter_hash(x, y, static_cast<int>(2 * k) + dir,
                                                               static_cast<int>(i), p.seed)
                                         : 0.0;
                        const double o = approx::jittered_offset_mm(taps, pt.range, i, xi) * scale;
                        const approx::TapTexels s = approx::tap_texels(pos + o, len);
                        const int ti[2] = {s.i0, s.i1};
                        const double tw[2] = {1 - s.t, s.t};
                        for (int j = 0; j < 2; ++j) {
                            if (tw[j] == 0) continue;
                            const size_t q = dir == 0 ? static_cast<size_t>(y) * w + ti[j]
                                                      : static_cast<size_t>(ti[j]) * w + x;
                            const double* v = &src[3 * q];
                            switch (p.mode) {
                                case SssEdgeMode::kNone:
                                    for (int ch = 0; ch < 3; ++ch)
                                        out[ch] += taps.weight[ch][i] * tw[j] * v[ch];
                                    break;
                                case SssEdgeMode::kFollowSurface: {
                                    // [Freude14 Eq. 4.12]: s_c = o_c (1 - t) + i_c t.
                                    const double dz =
                                        std::fabs(static_cast<double>(g.view_z[q]) - zc);
                                    const double t =
                                        std::min(1.0, p.follow_strength * dz / p.tan_half);
                                    for (int ch = 0; ch < 3; ++ch)
                                        out[ch] += taps.weight[ch][i] * tw[j] *
                                                   (v[ch] * (1 - t) + centre[ch] * t);
                                    break;
                                }
                                case SssEdgeMode::kReject: {
                                    const double dz =
                                        std::fabs(static_cast<double>(g.view_z[q]) - zc);
                                    if (g.material[q] != mat || !(dz <= p.reject_depth)) {
                                        dropped = true;
                                        break;
                                    }
                                    for (int ch = 0; ch < 3; ++ch) {
                                        out[ch] += taps.weight[ch][i] * tw[j] * v[ch];
                                        kept[ch] += taps.weight[ch][i] * tw[j];
                                    }
                                    break;
                                }
                            }
                        }
                    }
                    if (dropped)
                        for (int ch = 0; ch < 3; ++ch)
                            out[ch] = kept[ch] != 0 ? out[ch] * (pt.weight_sum[ch] / kept[ch])
                                                    : pt.weight_sum[ch] * centre[ch];
                    store(c, out.data());
                }
        });
    };

    for (size_t k = 0; k < rank; ++k) {
        // Horizontal: pixels without term k hold their input.
        pass(in, k, 0, [&](size_t c, const double* v) {
            for (int ch = 0; ch < 3; ++ch) tmp[3 * c + ch] = v ? v[ch] : in[3 * c + ch];
        });
        // Vertical, summed with the term's signs.
        pass(tmp, k, 1, [&](size_t c, const double* v) {
            if (!v) return;
            const int32_t mat = g.material[c];
            const SssTerm& t = *prep[static_cast<size_t>(mat)][k].term;
            for (int ch = 0; ch < 3; ++ch) acc[3 * c + ch] += t.sign[ch] * v[ch];
        });
    }

    std::vector<float> out(3 * n);
    for (size_t c = 0; c < n; ++c)
        for (int ch = 0; ch < 3; ++ch)
            out[3 * c + ch] =
                static_cast<float>(g.material[c] < 0 ? in[3 * c + ch] : acc[3 * c + ch]);
    return out;
}

}  // namespace ssslab::realtime
