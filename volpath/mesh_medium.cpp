#include "volpath/mesh_medium.h"

namespace ssslab::volpath {

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
