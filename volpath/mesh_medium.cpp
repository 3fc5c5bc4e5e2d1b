#include "volpath/mesh_medium.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ssslab::volpath {

namespace {

// The bounding box of a mesh's vertices.
void bounds(const TriangleMesh& m, double lo[3], double hi[3]) {
    constexpr double kInf = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k) {
        lo[k] = kInf;
        hi[k] = -kInf;
    }
    for (const Vec3& v : m.positions)
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], v[k]);
            hi[k] = std::max(hi[k], v[k]);
        }
}

}  // namespace

SurfaceDistanceGrid::SurfaceDistanceGrid(const EmbreeScene& scene, const TriangleMesh& shape)
    : scene_(&scene) {
    double lo[3], hi[3];
    bounds(shape, lo, hi);
    const Vec3 size{hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
    const double longest = std::max({size.x, size.y, size.z});
    if (!(longest > 0) || !std::isfinite(longest)) return;  // no cells: no balls
    h_ = longest / 64;
    for (int k = 0; k < 3; ++k) n_[k] = std::max(1, static_cast<int>(std::ceil(size[k] / h_)));
    lo_ = {lo[0], lo[1], lo[2]};
    cap_ = length(size);
    const std::size_t cells = static_cast<std::size_t>(n_[0]) * static_cast<std::size_t>(n_[1]) *
                              static_cast<std::size_t>(n_[2]);
    d_ = std::make_unique<std::atomic<float>[]>(cells);
    for (std::size_t i = 0; i < cells; ++i) d_[i].store(-1.0f, std::memory_order_relaxed);
}

bool SurfaceDistanceGrid::ball(const Vec3& p, Vec3& c, double& r) const {
    if (!d_) return false;
    int i[3];
    for (int k = 0; k < 3; ++k) {
        const double x = (p[k] - lo_[k]) / h_;
        if (!(x >= 0 && x < n_[k])) return false;
        i[k] = static_cast<int>(x);
    }
    const std::size_t cell = (static_cast<std::size_t>(i[2]) * static_cast<std::size_t>(n_[1]) +
                              static_cast<std::size_t>(i[1])) *
                                 static_cast<std::size_t>(n_[0]) +
                             static_cast<std::size_t>(i[0]);
    c = {lo_.x + (i[0] + 0.5) * h_, lo_.y + (i[1] + 0.5) * h_, lo_.z + (i[2] + 0.5) * h_};
    float d = d_[cell].load(std::memory_order_relaxed);
    if (d < 0) {
        double found = cap_;
        for (double radius = 2 * h_;; radius *= 2) {
            const double at = scene_->distance_to_surface(c, std::min(radius, cap_));
            if (at < std::min(radius, cap_) || radius >= cap_) {
                found = at;
                break;
            }
        }
        // Rounded down, so that the float is still a lower bound.
        d = static_cast<float>(found);
        if (static_cast<double>(d) > found) d = std::nextafter(d, 0.0f);
        d_[cell].store(d, std::memory_order_relaxed);
    }
    r = static_cast<double>(d) - scene_->epsilon();
    return r > 0.5 * std::sqrt(3.0) * h_;  // the ball holds the whole cell
}

bool SurfaceDistanceGrid::pays(const WalkRegion& r, const TriangleMesh& shape) {
    double lo[3], hi[3];
    bounds(shape, lo, hi);
    const double extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
    for (std::size_t c = 0; c < 3; ++c)
        if (r.albedo[c] >= 0.99 && extent * r.majorant[c] >= 16) return true;
    return false;
}

namespace {

// A smooth dielectric boundary; an exit ends the walk with its point, direction and normal.
template <int NC>
struct SmoothBoundary : WalkHooks {
    double eta = 1;  // outside over inside
    WalkBoundary exit;
    BoundaryAction boundary(WalkState<NC>& s, const WalkBoundary& b, RngStream& rng) {
        if (fresnel_reflects(s.w, b.n, eta, rng)) return BoundaryAction::kReflect;
        exit = b;
        return BoundaryAction::kExit;
    }
};

}  // namespace

template <int NC>
WalkResult walk_mesh_medium(const MeshMedium& m, Vec3 p, Vec3 w, RngStream& rng, int hero,
                            bool on_surface) {
    MeshGeometry geo;
    geo.scene = m.scene;
    geo.shape = m.shape;
    geo.inside = WalkRegion::make(m.sigma_t, m.sigma_s, m.g, m.density);
    geo.balls = m.balls;
    WalkRules rules;
    rules.long_events = m.long_events;
    rules.long_survival = m.long_survival;
    WalkState<NC> s;
    s.p = p;
    s.w = w;
    s.on_surface = on_surface;
    s.weights.hero = hero;
    s.weights.prob = m.hero_prob;
    s.weights.start(1.0);
    SmoothBoundary<NC> hooks;
    hooks.eta = m.eta_outside / m.eta_inside;
    const WalkEnd end = walk(geo, s, rules, rng, hooks);
    WalkResult r;
    r.events = s.events;
    for (int c = 0; c < NC; ++c) r.weight[static_cast<std::size_t>(c)] = s.weights.beta[c];
    r.fate = end == WalkEnd::kExited ? WalkResult::Fate::kExited
             : end == WalkEnd::kLost ? WalkResult::Fate::kLost
                                     : WalkResult::Fate::kAbsorbed;
    if (end == WalkEnd::kExited) {
        r.p = s.p;
        r.w = s.w;
        r.n = hooks.exit.n;
    }
    return r;
}

template WalkResult walk_mesh_medium<1>(const MeshMedium&, Vec3, Vec3, RngStream&, int, bool);
template WalkResult walk_mesh_medium<3>(const MeshMedium&, Vec3, Vec3, RngStream&, int, bool);

}  // namespace ssslab::volpath
