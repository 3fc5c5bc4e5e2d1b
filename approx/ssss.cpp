// SeparableSSS::calculateKernel() of Jorge Jimenez's separable-sss demo (iryoku/separable-sss,
// Demo/Code/SeparableSSS.cpp), ported operation for operation in single precision so that the
// presets shipped in its SeparableSSS.h come out to their printed digits [Freude14 Eq. 4.8].
#include "approx/models.h"

#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace ssslab::approx {

namespace {

using Vec3f = std::array<float, 3>;

// The demo's D3DXVECTOR3 arithmetic, component by component.
Vec3f scaled(float f, const Vec3f& v) {
    return {f * v[0], f * v[1], f * v[2]};
}
Vec3f added(const Vec3f& a, const Vec3f& b) {
    return {a[0] + b[0], a[1] + b[1], a[2] + b[2]};
}

// SeparableSSS::gaussian: a 2D Gaussian of the given variance at r / (0.001 + falloff), with pi
// written as 3.14f as in the demo.
Vec3f gaussian(const Vec3f& falloff, float variance, float r) {
    Vec3f g{};
    for (int i = 0; i < 3; ++i) {
        const float rr = r / (0.001f + falloff[static_cast<size_t>(i)]);
        g[static_cast<size_t>(i)] =
            std::exp((-(rr * rr)) / (2.0f * variance)) / (2.0f * 3.14f * variance);
    }
    return g;
}

// SeparableSSS::profile: the red channel of d'Eon & Luebke's three-layer skin profile without
// its narrowest Gaussian (0.233 at variance 0.0064), which the demo leaves to the strength.
Vec3f profile(const Vec3f& falloff, float r) {
    Vec3f p = scaled(0.100f, gaussian(falloff, 0.0484f, r));
    p = added(p, scaled(0.118f, gaussian(falloff, 0.187f, r)));
    p = added(p, scaled(0.113f, gaussian(falloff, 0.567f, r)));
    p = added(p, scaled(0.358f, gaussian(falloff, 1.99f, r)));
    p = added(p, scaled(0.078f, gaussian(falloff, 7.41f, r)));
    return p;
}

struct Sample {
    Vec3f rgb{};
    float w = 0;  // offset
};

}  // namespace

std::vector<Tap> ssss_demo_kernel(int samples, const SsssSkinParams& params) {
    if (samples < 2)
        throw std::invalid_argument("ssss_demo_kernel: need at least 2 samples, got " +
                                    std::to_string(samples));
    Vec3f strength{}, falloff{};
    for (size_t c = 0; c < 3; ++c) {
        const double t = params.strength[c], f = params.falloff[c];
        if (!(t >= 0 && t <= 1))
            throw std::invalid_argument("ssss_demo_kernel: strength outside [0, 1]");
        if (!(f >= 0) || !std::isfinite(f))
            throw std::invalid_argument("ssss_demo_kernel: falloff negative or not finite");
        strength[c] = static_cast<float>(t);
        falloff[c] = static_cast<float>(f);
    }
    const int n = samples;
    const auto at = [](int i) { return static_cast<size_t>(i); };

    const float range = n > 20 ? 3.0f : 2.0f;
    const float exponent = 2.0f;
    std::vector<Sample> kernel(at(n));

    // Offsets.
    const float step = 2.0f * range / static_cast<float>(n - 1);
    for (int i = 0; i < n; ++i) {
        const float o = -range + static_cast<float>(i) * step;
        const float sign = o < 0.0f ? -1.0f : 1.0f;
        kernel[at(i)].w =
            range * sign * std::fabs(std::pow(o, exponent)) / std::pow(range, exponent);
    }

    // Weights: the area each sample covers times the profile there.
    for (int i = 0; i < n; ++i) {
        const float w0 = i > 0 ? std::fabs(kernel[at(i)].w - kernel[at(i - 1)].w) : 0.0f;
        const float w1 = i < n - 1 ? std::fabs(kernel[at(i)].w - kernel[at(i + 1)].w) : 0.0f;
        const float area = (w0 + w1) / 2.0f;
        kernel[at(i)].rgb = scaled(area, profile(falloff, kernel[at(i)].w));
    }

    // The offset 0 comes first.
    const Sample centre = kernel[at(n / 2)];
    for (int i = n / 2; i > 0; --i) kernel[at(i)] = kernel[at(i - 1)];
    kernel[0] = centre;

    // Normalise each channel.
    Vec3f sum{0.0f, 0.0f, 0.0f};
    for (int i = 0; i < n; ++i) sum = added(sum, kernel[at(i)].rgb);
    for (int i = 0; i < n; ++i)
        for (size_t c = 0; c < 3; ++c) kernel[at(i)].rgb[c] /= sum[c];

    // The strength: lerp(1, kernel[0], t) for the centre, lerp(0, kernel[i], t) for the others.
    for (size_t c = 0; c < 3; ++c)
        kernel[0].rgb[c] = (1.0f - strength[c]) * 1.0f + strength[c] * kernel[0].rgb[c];
    for (int i = 1; i < n; ++i)
        for (size_t c = 0; c < 3; ++c) kernel[at(i)].rgb[c] *= strength[c];

    std::vector<Tap> taps;
    taps.reserve(at(n));
    for (const Sample& s : kernel)
        taps.push_back(Tap{static_cast<double>(s.w),
                           {static_cast<double>(s.rgb[0]), static_cast<double>(s.rgb[1]),
                            static_cast<double>(s.rgb[2])}});
    return taps;
}

}  // namespace ssslab::approx
