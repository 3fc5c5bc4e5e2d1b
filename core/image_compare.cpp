#include "core/image_compare.h"

#include "core/stats.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace ssslab {

namespace {

const ImageLayer& rgb_layer(const LayeredImage& im, const std::string& layer,
                            const std::string& source) {
    if (!im.has_layer(layer)) throw std::invalid_argument(source + ": no layer \"" + layer + "\"");
    const ImageLayer& l = im.layer(layer);
    if (l.channels() != 3)
        throw std::invalid_argument(source + ": layer \"" + layer + "\" is not RGB");
    return l;
}

}  // namespace

ImageEstimate estimate_with_stderr(const LayeredImage& image, const std::string& layer,
                                   const std::string& source) {
    const ImageLayer& m = rgb_layer(image, layer, source);
    const ImageLayer& s = rgb_layer(image, layer + ".stderr", source);
    ImageEstimate e;
    e.width = image.width();
    e.height = image.height();
    e.source = source;
    e.mean.assign(m.pixels().begin(), m.pixels().end());
    e.var.resize(e.mean.size());
    for (size_t i = 0; i < e.var.size(); ++i) {
        const double v = s.pixels()[i];
        e.var[i] = v * v;
    }
    return e;
}

ImageEstimate estimate_from_runs(const std::vector<LayeredImage>& runs, const std::string& layer,
                                 const std::string& source) {
    if (runs.size() < 2)
        throw std::invalid_argument(source + ": need at least two independent runs for a variance");
    ImageEstimate e;
    e.width = runs[0].width();
    e.height = runs[0].height();
    e.source = source;
    const size_t n = static_cast<size_t>(e.width) * static_cast<size_t>(e.height) * 3;
    std::vector<double> sum(n, 0.0), sum2(n, 0.0);
    for (const LayeredImage& r : runs) {
        if (r.width() != e.width || r.height() != e.height)
            throw std::invalid_argument(source + ": the runs differ in size");
        const ImageLayer& l = rgb_layer(r, layer, source);
        for (size_t i = 0; i < n; ++i) {
            const double v = l.pixels()[i];
            sum[i] += v;
            sum2[i] += v * v;
        }
    }
    const double K = static_cast<double>(runs.size());
    e.mean.resize(n);
    e.var.resize(n);
    for (size_t i = 0; i < n; ++i) {
        const double mu = sum[i] / K;
        e.mean[i] = mu;
        e.var[i] = std::max(0.0, (sum2[i] - K * mu * mu) / (K - 1)) / K;
    }
    return e;
}

double ImageComparison::p_min_corrected() const {
    return std::min(1.0, 3 * std::min({p[0], p[1], p[2]}));
}

double mean_pixel_variance(const ImageEstimate& e, int channel) {
    double sum = 0;
    const std::size_t n = e.var.size() / 3;
    for (std::size_t i = 0; i < n; ++i) sum += e.var[i * 3 + static_cast<std::size_t>(channel)];
    return n > 0 ? sum / static_cast<double>(n) : 0.0;
}

ImageMean image_mean(const ImageEstimate& e, int channel) {
    double sum = 0, var = 0;
    const std::size_t n = static_cast<std::size_t>(e.width) * static_cast<std::size_t>(e.height);
    for (std::size_t i = 0; i < n; ++i) {
        sum += e.mean[i * 3 + static_cast<std::size_t>(channel)];
        var += e.var[i * 3 + static_cast<std::size_t>(channel)];
    }
    const double npix = static_cast<double>(e.width) * e.height;
    return {sum / npix, std::sqrt(var) / npix};
}

ImageComparison compare_images(const ImageEstimate& a, const ImageEstimate& b, int block) {
    if (a.width != b.width || a.height != b.height)
        throw std::invalid_argument("images differ in size: " + a.source + " is " +
                                    std::to_string(a.width) + "x" + std::to_string(a.height) +
                                    ", " + b.source + " is " + std::to_string(b.width) + "x" +
                                    std::to_string(b.height));
    if (block < 1) throw std::invalid_argument("block size must be >= 1");
    ImageComparison r;
    r.block = block;
    const auto idx = [&](int x, int y, int c) {
        return (static_cast<size_t>(y) * static_cast<size_t>(a.width) + static_cast<size_t>(x)) *
                   3 +
               static_cast<size_t>(c);
    };
    for (int c = 0; c < 3; ++c) {
        const ImageMean ma = image_mean(a, c), mb = image_mean(b, c);
        const size_t k = static_cast<size_t>(c);
        r.mean_a[k] = ma.mean;
        r.se_a[k] = ma.se;
        r.mean_b[k] = mb.mean;
        r.se_b[k] = mb.se;
        const double se = std::hypot(r.se_a[k], r.se_b[k]);
        r.z_mean[k] = se > 0 ? (r.mean_a[k] - r.mean_b[k]) / se : 0.0;
    }
    double d2 = 0, n2 = 0, b2 = 0;
    for (int y0 = 0; y0 < a.height; y0 += block)
        for (int x0 = 0; x0 < a.width; x0 += block)
            for (int c = 0; c < 3; ++c) {
                double sa = 0, sb = 0, v = 0, n = 0;
                for (int y = y0; y < std::min(a.height, y0 + block); ++y)
                    for (int x = x0; x < std::min(a.width, x0 + block); ++x) {
                        const size_t i = idx(x, y, c);
                        sa += a.mean[i];
                        sb += b.mean[i];
                        v += a.var[i] + b.var[i];
                        n += 1;
                    }
                BlockDifference d;
                d.x0 = x0;
                d.y0 = y0;
                d.channel = c;
                d.a = sa / n;
                d.b = sb / n;
                d.se = std::sqrt(v) / n;
                // No noise on either side (an unlit or directly seen constant background; the
                // standard error of such a block is rounding, ~1e-8 of the value): left out if
                // the two agree to float precision, a deterministic difference otherwise.
                const double tol = 1e-6 * std::max(std::fabs(d.a), std::fabs(d.b));
                if (!(d.se > tol)) {
                    if (std::fabs(d.a - d.b) <= tol) {
                        ++r.skipped;
                        continue;
                    }
                    ++r.deterministic_differences;
                    d.se = tol > 0 ? tol : 1e-300;
                }
                d.z = (d.a - d.b) / d.se;
                r.chi2[static_cast<size_t>(c)] += d.z * d.z;
                ++r.dof[static_cast<size_t>(c)];
                r.max_abs_z = std::max(r.max_abs_z, std::fabs(d.z));
                d2 += (d.a - d.b) * (d.a - d.b);
                n2 += d.se * d.se;
                b2 += d.b * d.b;
                r.blocks.push_back(d);
            }
    for (size_t c = 0; c < 3; ++c)
        r.p[c] = r.deterministic_differences > 0 ? 0.0 : chi_square_p(r.chi2[c], r.dof[c]);
    r.rel_rms_diff = b2 > 0 ? std::sqrt(d2 / b2) : 0.0;
    r.rel_rms_noise = b2 > 0 ? std::sqrt(n2 / b2) : 0.0;
    return r;
}

NoiseCorrectedRms noise_corrected_rms(const std::vector<double>& a, const std::vector<double>& va,
                                      const std::vector<double>& b, const std::vector<double>& vb,
                                      double dof) {
    const std::size_t n = a.size();
    if (b.size() != n || (!va.empty() && va.size() != n) || (!vb.empty() && vb.size() != n))
        throw std::invalid_argument("noise_corrected_rms: values and variances differ in size");
    NoiseCorrectedRms r;
    r.n = n;
    if (n == 0) return r;
    // Var(t) = 4 d^2 v + 2 v^2 (+ 2 v^2 / dof, the spread of an estimated v), estimated without
    // bias: 4 t v for 4 d^2 v (E[t v] = d^2 v - 2 v^2 / dof, t and v independent for Gaussian
    // batch means), and v^2 / (1 + 2 / dof) for the true v^2. Clamping t at 0 instead would
    // overstate the error by ~20 % where the difference is within the noise.
    const double v2_scale =
        dof > 0 ? (2.0 * (1.0 + 1.0 / dof) + 8.0 / dof) / (1.0 + 2.0 / dof) : 2.0;
    double sum = 0, raw = 0, noise = 0, var = 0, var_noise = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const double d = a[i] - b[i];
        const double v = (va.empty() ? 0.0 : va[i]) + (vb.empty() ? 0.0 : vb[i]);
        const double t = d * d - v;
        sum += t;
        raw += d * d;
        noise += v;
        var += 4.0 * t * v + v2_scale * v * v;
        var_noise += v2_scale * v * v;
    }
    const double nn = static_cast<double>(n);
    r.ms = sum / nn;
    r.ms_se = std::sqrt(std::max(var, var_noise)) / nn;
    r.raw_rms = std::sqrt(raw / nn);
    r.noise_rms = std::sqrt(noise / nn);
    r.rms = std::sqrt(std::max(0.0, r.ms));
    r.rms_se =
        r.rms > 0 ? std::min(r.ms_se / (2.0 * r.rms), std::sqrt(r.ms_se)) : std::sqrt(r.ms_se);
    return r;
}

double max_relative_difference(const std::vector<float>& a, const std::vector<float>& b,
                               double floor_fraction) {
    if (a.size() != b.size()) throw std::invalid_argument("max_relative_difference: sizes differ");
    double top = 0, worst = 0;
    for (float v : b) top = std::max(top, static_cast<double>(std::fabs(v)));
    const double floor = floor_fraction * top;
    for (size_t i = 0; i < b.size(); ++i)
        worst = std::max(worst, std::fabs(static_cast<double>(a[i]) - b[i]) /
                                    std::max(floor, std::fabs(static_cast<double>(b[i]))));
    return worst;
}

}  // namespace ssslab
