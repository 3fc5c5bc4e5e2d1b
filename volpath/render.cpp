#include "volpath/render.h"

#include "core/error.h"
#include "core/light.h"
#include "core/rng.h"
#include "core/sobol.h"
#include "volpath/density_grid.h"
#include "volpath/embree_scene.h"
#include "volpath/mesh_medium.h"
#include "volpath/microfacet.h"
#include "volpath/render_guides.h"
#include "volpath/renderer.h"
#include "volpath/sampling.h"
#include "volpath/walk.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <memory>

namespace ssslab::volpath {

namespace {

// 3: NEE off the first rough boundary is "specular"; 4: NEE samples every light, Sobol points,
// sphere lights block the shadow rays of other lights; 5: absorption weighted in media whose
// every albedo is at least 0.9 (render_absorption); 6: the hero chosen at every entry into a
// medium by throughput x albedo (RenderHero), the environment sampled about a surface's normal
// by cos(theta) (RenderOptions::environment_cosine); 7: rays leave a surface from the point itself
// (rays_from_surface); 8: exit guides at scattering vertices (exit_guide); 9: and at a rough
// boundary's own vertices (boundary_guides); 10: and at a diffuse vertex straight after the way
// out of a guided medium (diffuse_guides); 11: a wide lobe beside each narrow one (wide_lobes).
constexpr const char* kEngineVersion = "volpath-render-11";
constexpr std::uint32_t kRenderDomain = rng_domain::kVolpath + 0x100;
constexpr int kMaxBatchSpp = 3 * 1024;  // the largest automatic batch (RenderOptions::batch_spp)

}  // namespace

namespace render_detail {

Renderer::Renderer(const Scene& s, const RenderOptions& o) : scene(s), opt(o) {
    width = o.width > 0 ? o.width : s.camera.width;
    height = o.height > 0 ? o.height : s.camera.height;
    std::vector<const TriangleMesh*> meshes;
    for (const SceneShape& sh : s.shapes) meshes.push_back(&sh.mesh);
    es = std::make_unique<EmbreeScene>(meshes);
    eps = es->epsilon();
    for (const SceneLight& sl : s.lights) lights.emplace_back(sl);
    sel = o.nee_all_lights || lights.empty() ? 1.0 : 1.0 / static_cast<double>(lights.size());
    for (std::size_t j = 0; j < lights.size() && guide_lights.size() < kMaxGuides; ++j) {
        if (lights[j].subtends_cone()) guide_lights.push_back(static_cast<int>(j));
    }
    for (const SceneShape& sh : s.shapes) {
        const SceneMaterial& m = s.materials[static_cast<size_t>(sh.material)];
        if (m.kind != SceneMaterial::Kind::kMedium) {
            shape_medium.push_back(-1);
            continue;
        }
        MediumData md;
        for (int c = 0; c < 3; ++c) {
            const size_t i = static_cast<size_t>(c);
            md.sigma_s[i] = s.per_world_unit(m.medium.sigma_s_per_cm[i]);
            md.sigma_t[i] = md.sigma_s[i] + s.per_world_unit(m.medium.sigma_a_per_cm[i]);
            md.g[i] = m.medium.g[i];
        }
        md.same_g = md.g[0] == md.g[1] && md.g[1] == md.g[2];
        md.absorption = render_absorption(md.sigma_s.data(), md.sigma_t.data(), o.absorption);
        md.eta = m.medium.eta;
        if (!m.density_file.empty()) {
            try {
                md.density = DensityGrid::load(m.density_file, m.density_grid);
            } catch (const InputError& e) {
                throw InputError(m.where, "density_vdb", e.what());
            }
        }
        md.alpha = m.boundary().alpha;
        md.region = WalkRegion::make(md.sigma_t, md.sigma_s, md.g, md.density.get());
        md.guided = o.exit_guide && md.eta != 1.0 && md.alpha > 0 && md.same_g && !md.density &&
                    !guide_lights.empty();
        shape_medium.push_back(static_cast<int>(media.size()));
        if (o.skip_queries_in_balls && SurfaceDistanceGrid::pays(md.region, sh.mesh)) {
            shape_balls.resize(s.shapes.size());
            shape_balls[shape_medium.size() - 1] =
                std::make_unique<SurfaceDistanceGrid>(*es, sh.mesh);
        }
        media.push_back(md);
    }
    for (int mi : shape_medium) passable_shape.push_back(mi >= 0 && passable(mi) ? 1 : 0);
    has_passable =
        std::find(passable_shape.begin(), passable_shape.end(), 1) != passable_shape.end();
    const SceneCamera& c = s.camera;
    cam_pos = c.position;
    cam_f = normalize(c.target - c.position);
    cam_r = normalize(cross(cam_f, c.up));
    cam_u = cross(cam_r, cam_f);
    tan_half = std::tan(0.5 * c.fov_y_deg * kPi / 180);
    aspect = static_cast<double>(width) / height;
}

// Per-channel transmittance from o along wi up to tmax through index-matched homogeneous
// media (`start_medium`: the one o is in, or -1); false if a surface blocks the way.
// `leaving`: the triangle o lies on (skipped), or none. One occlusion query that passes
// through the passable boundaries and records them (EmbreeScene::crossings); the crossings,
// in order, attenuate as a ray stepped from each to the next would (the loop of the option
// off, which restarts eps beyond each boundary, and the fallback for more crossings than
// the buffer holds).
bool Renderer::shadow(const Vec3& o, const Vec3& wi, double tmax, int start_medium, RGB& T,
                      std::uint64_t& rays, TriangleRef leaving) const {
    T = {1, 1, 1};
    int inside = start_medium;
    double t0 = 0;
    auto attenuate = [&](int mi, double len) {
        const MediumData& md = media[static_cast<size_t>(mi)];
        for (int c = 0; c < 3; ++c)
            T[static_cast<size_t>(c)] *= std::exp(-md.sigma_t[static_cast<size_t>(c)] * len);
    };
    // A boundary crossed at distance t (its triangle's normal n).
    auto cross = [&](int mi, double t, const Vec3& n) {
        if (dot(wi, n) < 0) {  // entering
            inside = mi;
            t0 = t;
        } else {
            if (inside == mi) attenuate(mi, t - t0);
            inside = -1;
        }
    };
    bool stepped = !opt.rays_from_surface;
    if (!stepped) {
        constexpr std::size_t kCap = 64;
        EmbreeScene::Crossing buf[kCap];
        std::size_t n = 0;
        ++rays;
        const auto through = es->crossings(o, wi, 0, tmax, leaving, passable_shape, buf, kCap, n);
        if (through == EmbreeScene::Through::kBlocked) return false;
        if (through == EmbreeScene::Through::kTooMany) {
            stepped = true;
        } else {
            std::sort(buf, buf + n, [](const auto& a, const auto& b) {
                return a.t < b.t ||
                       (a.t == b.t &&
                        (a.shape < b.shape || (a.shape == b.shape && a.triangle < b.triangle)));
            });
            // As the stepping loop meets them: after a crossing the next query starts at it,
            // skipping its triangle and the hits within rounding (a hit reported twice too).
            const EmbreeScene::Crossing* prev = nullptr;
            for (std::size_t k = 0; k < n; ++k) {
                const EmbreeScene::Crossing& c = buf[k];
                if (prev && (!(c.t >= static_cast<float>(prev->t + es->rounding())) ||
                             (c.shape == prev->shape && c.triangle == prev->triangle)))
                    continue;
                cross(shape_medium[c.shape], c.t, es->normal(c.shape, c.triangle));
                prev = &c;
            }
        }
    }
    if (stepped) {  // nothing crossed yet: T and inside as they started
        double t = 0;
        for (int k = 0; k < 10000; ++k) {
            ++rays;
            const RayHit hit = es->intersect(o, wi, t, tmax, leaving);
            if (!hit.hit()) break;
            const int mi = shape_medium[hit.shape];
            if (mi < 0 || !passable(mi)) return false;
            cross(mi, hit.t, hit.normal);
            // On from the boundary point, its triangle skipped (and hits within rounding);
            // before volpath-render-7 (the option) eps beyond it, which missed the exit of a
            // medium thinner than eps.
            if (opt.rays_from_surface) {
                t = hit.t;
                leaving = {hit.shape, hit.triangle};
            } else {
                t = hit.t + eps;
            }
        }
    }
    if (inside >= 0 && std::isfinite(tmax)) attenuate(inside, tmax - t0);
    return true;
}

// Next-event estimation from p: every light, or one chosen uniformly (nee_all_lights);
// `f_of(wi)` gives the BSDF (or phase function) value times |cos| per channel and
// `pdf_of(wi)` the sampling density of the other strategy; `at`: the surface p lies on
// (the normal of the side the shadow ray leaves from and the triangle), null at a point
// inside a medium (`medium` then names it); `share`: the exit guide's part in the MIS of
// the lights it aims at (an exit vertex it aimed at), or none.
template <class F, class P>
void Renderer::nee(const Vec3& p, const SurfaceAt* at, RngStream& rng, const double* beta, F f_of,
                   P pdf_of, RGB& out, std::uint64_t& rays, int medium,
                   const GuideShare& share) const {
    if (lights.empty()) return;
    if (opt.nee_all_lights) {
        for (const Light& l : lights)
            nee_light(l, p, at, rng, beta, f_of, pdf_of, out, rays, medium, share);
        return;
    }
    const std::size_t j =
        std::min(lights.size() - 1,
                 static_cast<std::size_t>(rng.uniform() * static_cast<double>(lights.size())));
    nee_light(lights[j], p, at, rng, beta, f_of, pdf_of, out, rays, medium, share);
}

// One light's shadow ray of nee(), its MIS weight against the other strategies.
template <class F, class P>
void Renderer::nee_light(const Light& light, const Vec3& p, const SurfaceAt* at, RngStream& rng,
                         const double* beta, F& f_of, P& pdf_of, RGB& out, std::uint64_t& rays,
                         int medium, const GuideShare& share) const {
    const double u1 = rng.uniform(), u2 = rng.uniform();
    const LightSample ls = light.sample(p, u1, u2, env_normal(at ? &at->n : nullptr));
    if (!ls.ok) return;
    if (at && !(dot(ls.wi, at->n) > 0)) return;
    const RGB fc = f_of(ls.wi);
    if (!(fc[0] > 0 || fc[1] > 0 || fc[2] > 0)) return;
    RGB T{1, 1, 1};
    if (!reaches(light, p, at, ls, medium, T, rays)) return;
    double w = 1, pl = 1;
    if (ls.pdf > 0) {
        pl = sel * ls.pdf;
        w = share.weight(&light, pl, pdf_of(ls.wi), ls.pdf);
    } else {
        pl = sel;
    }
    for (int c = 0; c < 3; ++c)
        out[static_cast<size_t>(c)] += beta[c] * fc[static_cast<size_t>(c)] *
                                       ls.value[static_cast<size_t>(c)] * w / pl *
                                       T[static_cast<size_t>(c)];
}

// Emission seen by a ray that left `from` in direction d and escaped (no geometry, no sphere
// light): environment and disc lights, weighted against light sampling if NEE was done.
void Renderer::add_escape(const Vec3& from, const Vec3* from_normal, const Vec3& d, bool prev_nee,
                          double prev_pdf, const double* beta, RGB& out,
                          const GuideShare& share) const {
    for (const Light& l : lights) {
        if (l.seen_escaping(d)) {
            const double pl = l.pdf(from, d, from_normal);
            const double w = prev_nee ? share.weight(&l, prev_pdf, sel * pl, pl) : 1.0;
            for (int c = 0; c < 3; ++c)
                out[static_cast<size_t>(c)] += beta[c] * l.L[static_cast<size_t>(c)] * w;
        }
    }
}

// A surface vertex at p (shape `shape`, its normal n), reached along the path's direction
// from either side of a medium's boundary or from outside a diffuse surface: the surface
// model, NEE, the next direction and the throughput roulette. False: the path ends.
bool Renderer::vertex(CameraPath& c, const Vec3& p, Vec3 n, TriangleRef tri) const {
    const std::uint32_t shape = tri.shape;
    const bool guided_arrival = c.guide_armed;
    c.guide_armed = false;
    const bool plate_arrival = c.plate_armed, left_guided_arrival = c.left_guided;
    c.plate_armed = c.left_guided = false;
    c.exit_share = {};
    if (opt.max_depth > 0 && c.depth >= opt.max_depth) return false;
    const int mi = shape_medium[shape];
    if (mi < 0) {  // diffuse, two-sided
        if (c.medium >= 0) return false;
        diffuse_vertex(c, p, n, tri, left_guided_arrival);
    } else if (!boundary_vertex(c, p, n, tri, mi, guided_arrival, plate_arrival)) {
        return false;
    }
    // Russian roulette on the throughput.
    double* beta = c.ws.weights.beta;
    if (c.depth + 1 >= opt.roulette_depth) {
        const double m = std::max({beta[0], beta[1], beta[2]});
        if (!(m > 0) || !std::isfinite(m)) return false;
        if (m < 1) {
            const double survive = std::max(0.05, m);
            if (!(c.rng.uniform() < survive)) return false;
            for (int k = 0; k < 3; ++k) beta[k] /= survive;
        }
    }
    ++c.depth;
    return true;
}

// vertex() on a diffuse surface: NEE, the cosine-weighted next direction, and straight from a
// guided medium's way out the diffuse guide (volpath-render-10).
void Renderer::diffuse_vertex(CameraPath& c, const Vec3& p, Vec3 n, TriangleRef tri,
                              bool left_guided_arrival) const {
    RngStream& rng = c.rng;
    double* beta = c.ws.weights.beta;
    Vec3& d = c.ws.w;
    const Vec3 wo = -d;
    const SceneMaterial& m = scene.materials[static_cast<size_t>(scene.shapes[tri.shape].material)];
    if (dot(n, wo) < 0) n = -n;
    const SurfaceAt at{n, tri};
    RGB e{};
    nee(
        p, &at, rng, beta,
        [&](const Vec3& wi) {
            const double cs = std::max(0.0, dot(wi, n)) / kPi;
            return RGB{m.albedo[0] * cs, m.albedo[1] * cs, m.albedo[2] * cs};
        },
        [&](const Vec3& wi) { return std::max(0.0, dot(wi, n)) / kPi; }, e, c.rays);
    flush(c, e);
    const double u1 = rng.uniform(), u2 = rng.uniform();
    const Vec3 wl = sample_cosine_hemisphere(u1, u2);
    d = Frame(n).world(wl);
    c.prev_pdf = wl.z / kPi;
    c.prev_nee = true;
    c.nee_pos = p;
    c.nee_normal = n;
    c.nee_on_surface = true;
    for (int k = 0; k < 3; ++k) beta[k] *= m.albedo[static_cast<size_t>(k)];
    // Straight from a guided medium's way out: the diffuse guide (volpath-render-10).
    if (left_guided_arrival) run_diffuse_guide(c, p, n, tri);
    leave_outside(c, p, n, tri);
}

// vertex() on the dielectric boundary of medium mi: a smooth one's Fresnel choice, or a rough
// one's NEE, exit guide and BSDF sample (rough_boundary); then into the medium or out of it.
// False: the path ends.
bool Renderer::boundary_vertex(CameraPath& c, const Vec3& p, const Vec3& n, TriangleRef tri, int mi,
                               bool guided_arrival, bool plate_arrival) const {
    const std::uint32_t shape = tri.shape;
    double* beta = c.ws.weights.beta;
    Vec3& d = c.ws.w;  // fresnel_reflects and rough_boundary turn it
    const MediumData& md = media[static_cast<size_t>(mi)];
    const bool outside = dot(-d, n) > 0;
    bool transmitted = false, reflected = false;
    ExitGuide here;  // this vertex's exit guide (rough boundaries)
    bool here_guided = false;
    if (md.alpha == 0) {
        // The smooth boundary of every engine's walk (walk_mesh_medium's too).
        const double eta = md.eta;  // inside over outside (outside index 1)
        const double eta_side = outside ? eta : 1 / eta;
        if (fresnel_reflects(d, outside ? -n : n, eta_side, c.rng)) {
            reflected = true;
        } else {
            for (int k = 0; k < 3; ++k) beta[k] /= eta_side * eta_side;  // radiance
            transmitted = true;
        }
        // An index-matched boundary is no vertex: NEE before it still stands.
        if (!passable(mi)) c.prev_nee = false;
    } else if (!rough_boundary(c, p, n, tri, md, outside, guided_arrival, plate_arrival, here,
                               here_guided, reflected, transmitted)) {
        return false;
    }
    if (c.depth == 0 && reflected) c.specular_path = true;
    if (transmitted) {
        if (c.medium < 0) {
            c.medium = mi;
            c.medium_shape = static_cast<int>(shape);
            if (opt.hero == RenderHero::kThroughputAlbedo) {
                // From the stream, not a Sobol dimension: the walk's first numbers keep the
                // pairs they had.
                const double u = c.rng.stream_uniform();
                c.ws.weights.choose_hero_by_throughput(md.region.albedo,
                                                       c.entered ? u : (c.hero + u) / 3);
            }
            c.entered = true;
        } else {
            c.medium = -1;
            c.medium_shape = -1;
        }
    }
    if (c.medium >= 0) {
        // Into a medium (entering, or reflected inside): from the surface point itself,
        // skipping hits closer than eps. An origin moved off the surface would start every
        // walk eps deep, a bias of sigma_t eps (measured: 3.7 % of the single scattering of
        // an index-matched half-space with sigma_t 1/mm at eps = 4e-5 of a 1 m scene).
        c.ws.p = p;
        c.ws.on_surface = true;
        // The walk goes on from this vertex of a rough boundary: its exit guide (above)
        // takes part in the MIS of the exit it reaches straight from here.
        if (here_guided) {
            c.guide = here;
            c.guide_armed = true;
        }
    } else {
        leave_outside(c, p, dot(d, n) > 0 ? n : -n, tri);
    }
    return true;
}

// boundary_vertex() on a rough (GGX) boundary: NEE through it, this vertex's exit guide
// (here, here_guided), the BSDF sample. False: the path ends.
bool Renderer::rough_boundary(CameraPath& c, const Vec3& p, const Vec3& n, TriangleRef tri,
                              const MediumData& md, bool outside, bool guided_arrival,
                              bool plate_arrival, ExitGuide& here, bool& here_guided,
                              bool& reflected, bool& transmitted) const {
    RngStream& rng = c.rng;
    double* beta = c.ws.weights.beta;
    Vec3& d = c.ws.w;
    const Vec3 wo = -d;
    const Frame fr(n);
    const Vec3 wo_l = fr.local(wo);
    const double eta = md.eta;  // inside over outside (outside index 1)
    // Light sampled at the first boundary from outside is its reflection: the "specular"
    // layer's (without this it went into "radiance" only).
    const bool first_reflection = c.depth == 0 && outside && !c.entered;
    if (first_reflection) c.specular_path = true;
    const SurfaceAt at{n, tri};
    // Straight from a guided vertex to this exit: the guide's part.
    const GuideShare share = guided_arrival && !outside ? arrival_share(c, p, md) : GuideShare{};
    RGB e{};
    nee(
        p, &at, rng, beta,
        [&](const Vec3& wi) {
            const double f =
                rough_dielectric_f(wo_l, fr.local(wi), eta, md.alpha, TransportMode::kRadiance) *
                std::abs(dot(wi, n));
            return RGB{f, f, f};
        },
        [&](const Vec3& wi) { return rough_dielectric_pdf(wo_l, fr.local(wi), eta, md.alpha); }, e,
        c.rays, -1, share);
    flush(c, e);
    // The exit guide of this vertex (volpath-render-9), whatever the walk's sample below does.
    here_guided = boundary_guide(c, p, n, tri, md, outside, plate_arrival, here);
    if (first_reflection) c.specular_path = false;  // decided by the sample below
    const double uc = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
    const auto smp =
        sample_rough_dielectric(wo_l, eta, md.alpha, uc, u1, u2, TransportMode::kRadiance);
    if (!smp) return false;
    const double wgt = smp->f * std::abs(smp->wi.z) / smp->pdf;
    for (int k = 0; k < 3; ++k) beta[k] *= wgt;
    d = fr.world(smp->wi);
    c.prev_pdf = smp->pdf;
    c.prev_nee = true;
    c.nee_pos = p;
    c.nee_normal = n;
    c.nee_on_surface = true;
    reflected = smp->reflection;
    transmitted = !smp->reflection;
    if (transmitted && !outside) {
        c.exit_share = share;
        c.left_guided = md.guided;
    }
    return true;
}

// Inside a medium: what the walk does at its boundary (vertex()), at its scattering vertices
// (NEE inside index-matched media, MIS with phase sampling; the exit guide behind rough
// boundaries) and after sampling the phase function.
struct Renderer::PathHooks : WalkHooks {
    const Renderer& R;
    CameraPath& c;
    PathHooks(const Renderer& r, CameraPath& path) : R(r), c(path) {}
    // The density with which phase sampling picks a direction, as the hero MIS sees it: the
    // mixture of the channels' phase functions weighted by their probabilities to be the
    // hero times their path densities so far (prob x q), which does not depend on the hero;
    // the MIS weights of NEE against phase sampling use it, so that they sum to one
    // whichever channel is the hero (with per-channel g too).
    double phase_mix(const WalkState<3>& s, double mu_l) const {
        const MediumData& md = R.media[static_cast<size_t>(c.medium)];
        if (md.same_g) return hg_pdf(md.g[0], mu_l);
        const double* qq = s.weights.q;
        const auto& pr = s.weights.prob;
        double v = 0, sum = 0;
        for (int k = 0; k < 3; ++k) {
            const double wc = pr[static_cast<size_t>(k)] * qq[k];
            sum += wc;
            v += wc * hg_pdf(md.g[static_cast<size_t>(k)], mu_l);
        }
        return v / sum;
    }
    BoundaryAction boundary(WalkState<3>& s, const WalkBoundary& b, RngStream&) {
        if (!R.vertex(c, s.p, b.n, TriangleRef{b.shape, b.triangle})) return BoundaryAction::kEnd;
        return c.medium >= 0 ? BoundaryAction::kReflect : BoundaryAction::kExit;
    }
    // Analog absorption by the hero's albedo. Where NEE is done at a vertex (index-matched
    // media) the decision waits until after it, and the NEE carries the survival
    // probability instead: its expectation over the decision, so that light is collected at
    // every collision, not only at the few that survive in an absorbing medium. Behind a
    // rough boundary the exit guide's estimator is done there the same way.
    bool vertex_nee(const WalkState<3>&) const {
        return R.passable(c.medium) || R.media[static_cast<size_t>(c.medium)].guided;
    }
    void at_vertex(WalkState<3>& s, double survive, RngStream& rng) {
        const MediumData& md = R.media[static_cast<size_t>(c.medium)];
        const double* beta = s.weights.beta;
        const double bs[3] = {beta[0] * survive, beta[1] * survive, beta[2] * survive};
        const Vec3 din = s.w;
        RGB e{};
        if (md.guided) {
            // The exit it aims at is a surface vertex: none beyond max_depth (where the path
            // ends at its next vertex, before any use of the guide).
            if (R.opt.max_depth > 0 && c.depth >= R.opt.max_depth) return;
            ExitGuide& guide = c.guide;
            guide.aimed = false;
            guide.prob = kExitGuideProb;
            guide.surface = false;
            guide.tri = TriangleRef{};
            guide.z = s.p;
            guide.din = s.w;
            guide.pq = R.inside_probabilities(s);
            R.run_exit_guide(guide, md, c.medium_shape, bs, rng, e, c.rays);
            flush(c, e);
            return;
        }
        R.nee(
            s.p, nullptr, rng, bs,
            [&](const Vec3& wi) {
                const double mu_l = dot(din, wi);
                return RGB{hg_pdf(md.g[0], mu_l), hg_pdf(md.g[1], mu_l), hg_pdf(md.g[2], mu_l)};
            },
            [&](const Vec3& wi) { return phase_mix(s, dot(din, wi)); }, e, c.rays, c.medium);
        flush(c, e);
    }
    void scattered(const WalkState<3>& s, double mu) {
        c.guide_armed = R.media[static_cast<size_t>(c.medium)].guided;
        c.prev_pdf = phase_mix(s, mu);
        c.prev_nee = R.passable(c.medium);
        c.nee_pos = s.p;
        c.nee_on_surface = false;
    }
};

// One camera path through pixel (x, y); tally += its contributions. Outside media the
// loop below; inside a medium the one walk of volpath/walk.h, whose boundary hook is the
// same surface vertex as a hit from outside.
std::uint64_t Renderer::trace(int x, int y, int hero, RngStream& rng, double* T) const {
    CameraPath c(hero, rng, T);
    const double jx = rng.uniform(), jy = rng.uniform();
    const double ndc_x = (2 * (x + jx) / width - 1) * tan_half * aspect;
    const double ndc_y = (1 - 2 * (y + jy) / height) * tan_half;
    WalkState<3>& ws = c.ws;
    ws.p = cam_pos;
    ws.w = normalize(cam_f + cam_r * ndc_x + cam_u * ndc_y);
    ws.weights.hero = hero;
    ws.weights.start(1.0);
    Vec3& o = ws.p;
    Vec3& d = ws.w;
    const double* beta = ws.weights.beta;
    PathHooks hooks(*this, c);
    WalkRules rules;
    rules.flight = FlightRule::kResample;
    rules.long_events = opt.long_path_events;

    while (c.depth < 100000) {
        if (c.medium >= 0) {
            MeshGeometry geo;
            geo.scene = es.get();
            geo.shape = static_cast<std::uint32_t>(c.medium_shape);
            geo.inside = media[static_cast<size_t>(c.medium)].region;
            if (!shape_balls.empty())
                geo.balls = shape_balls[static_cast<size_t>(c.medium_shape)].get();
            rules.absorption = media[static_cast<size_t>(c.medium)].absorption;
            const std::uint64_t before = ws.queries;
            const WalkEnd end = walk(geo, ws, rules, rng, hooks);
            c.rays += ws.queries - before;
            if (end != WalkEnd::kExited) return c.rays;
            continue;
        }
        ++c.rays;
        const RayHit hit = es->intersect(o, d, ws.on_surface ? eps : 0.0, kInf, c.leave);
        c.leave = TriangleRef{};
        if (c.depth == 0 && hit.hit()) {
            T[RenderLayout::kDepth] += hit.t;
            for (int k = 0; k < 3; ++k) T[RenderLayout::kNormal + k] += hit.normal[k];
        }
        // Sphere lights are not in the BVH: the nearest of them, if before the geometry.
        double tl = kInf;
        const Light* hit_light = nearest_light_surface(lights, o, d, tl);
        if (hit_light && tl < hit.t) {
            const double pl = hit_light->pdf(c.nee_pos, d);
            const double w =
                c.prev_nee ? c.exit_share.weight(hit_light, c.prev_pdf, sel * pl, pl) : 1.0;
            RGB e{};
            for (int k = 0; k < 3; ++k)
                e[static_cast<size_t>(k)] = beta[k] * hit_light->L[static_cast<size_t>(k)] * w;
            flush(c, e);
            return c.rays;
        }
        if (!hit.hit()) {
            RGB e{};
            add_escape(c.nee_pos, env_normal(c.nee_on_surface ? &c.nee_normal : nullptr), d,
                       c.prev_nee, c.prev_pdf, beta, e, c.exit_share);
            flush(c, e);
            return c.rays;
        }
        const Vec3 p = o + d * hit.t;
        if (shape_medium[hit.shape] >= 0 && !(dot(d, hit.normal) < 0)) {
            // A medium's boundary met from inside while outside. Within a few epsilons: the
            // restart point slipped across a concave crease of this mesh; cross back and go
            // on. Farther: a leak; the path ends.
            if (hit.t < 4 * eps) {
                o = p;
                ws.on_surface = true;
                continue;
            }
            return c.rays;
        }
        if (!vertex(c, p, hit.normal, TriangleRef{hit.shape, hit.triangle})) return c.rays;
    }
    return c.rays;
}

}  // namespace render_detail

namespace {

using render_detail::Renderer;

// Radiance channel i % 3 of pixel i / 3 in the tally (RenderLayout).
std::size_t radiance_element(std::size_t i) {
    return (i / 3) * RenderLayout::kPerPixel + RenderLayout::kRadiance + i % 3;
}

}  // namespace

Absorption render_absorption(const double sigma_s[3], const double sigma_t[3],
                             std::optional<Absorption> requested) {
    if (requested) return *requested;
    for (int c = 0; c < 3; ++c)
        if (!(sigma_s[c] >= kWeightedAbsorptionAlbedo * sigma_t[c])) return Absorption::kAnalog;
    return Absorption::kWeighted;
}

const char* render_engine_version() {
    return kEngineVersion;
}

void check_renderable(const Scene& scene) {
    if (!scene.delta_light_through_smooth_boundary()) return;
    for (const SceneLight& l : scene.lights)
        if (Light(l).is_delta())
            throw InputError(l.where, "type",
                             std::string("a ") + to_string(l.type) +
                                 " light cannot reach a medium behind a smooth boundary in a path "
                                 "tracer (it would render that medium black): give the medium a "
                                 "roughness (e.g. 0.05), the light an angular_radius_deg, or use a "
                                 "sphere light");
}

const char* to_string(RenderHero h) {
    return name_of(h).data();
}

const char* to_string(RenderErrorMeasure m) {
    return name_of(m).data();
}

RelativeError radiance_rel_error(const std::vector<double>& mean, const std::vector<double>& se) {
    const std::size_t n = mean.size() / RenderLayout::kPerPixel * 3;
    return relative_error(
        n, [&](std::size_t i) { return mean[radiance_element(i)]; },
        [&](std::size_t i) { return se[radiance_element(i)]; });
}

RelativeError radiance_rel_error(const LayeredImage& image) {
    const auto L = image.layer("radiance").pixels();
    const auto E = image.layer("radiance.stderr").pixels();
    return relative_error(
        L.size(), [&](std::size_t i) { return L[i]; }, [&](std::size_t i) { return E[i]; });
}

MeasuredError measured_error(const LayeredImage& run, const LayeredImage& reference) {
    if (reference.width() != run.width() || reference.height() != run.height())
        throw std::invalid_argument("the reference image is " + std::to_string(reference.width()) +
                                    " x " + std::to_string(reference.height()) + ", the render " +
                                    std::to_string(run.width()) + " x " +
                                    std::to_string(run.height()));
    MeasuredError m;
    m.own = radiance_rel_error(run);
    m.reference = radiance_rel_error(reference);
    const auto L = run.layer("radiance").pixels();
    const auto E = run.layer("radiance.stderr").pixels();
    const auto R = reference.layer("radiance").pixels();
    const auto F = reference.layer("radiance.stderr").pixels();
    double d2 = 0, r2 = 0, f2 = 0;
    std::vector<double> z2;
    z2.reserve(L.size());
    for (std::size_t i = 0; i < L.size(); ++i) {
        const double d = static_cast<double>(L[i]) - R[i];
        d2 += d * d;
        r2 += static_cast<double>(R[i]) * R[i];
        f2 += static_cast<double>(F[i]) * F[i];
        const double v = static_cast<double>(E[i]) * E[i] + static_cast<double>(F[i]) * F[i];
        if (R[i] > 0 && v > 0) z2.push_back(d * d / v);
    }
    if (!(r2 > 0)) throw std::invalid_argument("the reference image is black");
    m.rel_rmse = std::sqrt(d2 / r2);
    m.rel_rmse_corrected = std::sqrt(std::max(0.0, (d2 - f2) / r2));
    m.counted = z2.size();
    if (!z2.empty()) {
        const auto mid = z2.begin() + static_cast<std::ptrdiff_t>(z2.size() / 2);
        std::nth_element(z2.begin(), mid, z2.end());
        constexpr double kChi2OneDofMedian = 0.45493642311957;
        m.z2_median_ratio = *mid / kChi2OneDofMedian;
        m.median_pixel = m.own.median * std::sqrt(m.z2_median_ratio);
    }
    return m;
}

int render_batch_spp(const RenderOptions& o) {
    if (o.batch_spp != 0) {
        if (o.batch_spp < 0 || o.batch_spp % 3 != 0)
            throw std::invalid_argument("batch_spp must be a positive multiple of 3, got " +
                                        std::to_string(o.batch_spp));
        return o.batch_spp;
    }
    const bool count_only = !o.budget.seconds && !o.budget.rel_error;
    if (!count_only) return 3;  // a time or error budget: as many batches as can be
    const std::int64_t spp = o.budget.samples ? *o.budget.samples : 64;
    int b = 3;
    while (b < kMaxBatchSpp && static_cast<std::int64_t>(2 * b) * 32 <= spp) b *= 2;
    return b;
}

namespace {

std::string fingerprint_with_batch(const Scene& scene, const RenderOptions& o, int batch_spp) {
    ContentKey k("render-checkpoint");
    k.add("engine", kEngineVersion)
        .add("seed", o.seed)
        .add("width", o.width > 0 ? o.width : scene.camera.width)
        .add("height", o.height > 0 ? o.height : scene.camera.height)
        .add("roulette_depth", o.roulette_depth)
        .add("long_path_events", o.long_path_events)
        .add("index_matched_nee", o.index_matched_nee)
        .add("samples_per_batch", batch_spp)
        .add("nee", o.nee_all_lights ? "all lights" : "one light")
        .add("sampler", std::string(name_of(o.sampler)));
    // Only when set, so that the keys of existing checkpoints stay what they were.
    if (o.max_depth != 0) k.add("max_depth", o.max_depth);
    if (o.absorption) k.add("absorption", to_string(*o.absorption));
    if (o.hero != RenderHero::kThroughputAlbedo) k.add("hero", to_string(o.hero));
    if (!o.environment_cosine) k.add("environment_cosine", false);
    if (!o.rays_from_surface) k.add("rays_from_surface", false);
    if (!o.exit_guide) k.add("exit_guide", false);
    if (o.exit_guide && !o.boundary_guides) k.add("boundary_guides", false);
    if (o.exit_guide && o.boundary_guides && !o.diffuse_guides) k.add("diffuse_guides", false);
    if (o.exit_guide && !o.wide_lobes) k.add("wide_lobes", false);
    add_to_key(k, scene);
    return k.text();
}

}  // namespace

std::string render_fingerprint(const Scene& scene, const RenderOptions& o) {
    return fingerprint_with_batch(scene, o, render_batch_spp(o));
}

RenderResult render(const Scene& scene, const RenderOptions& o) {
    check_renderable(scene);
    const Renderer R(scene, o);
    RenderResult out;
    out.width = R.width;
    out.height = R.height;
    for (std::size_t i = 0; i < scene.shapes.size(); ++i) {
        const int m = R.shape_medium[i];
        const std::string& name =
            scene.materials[static_cast<size_t>(scene.shapes[i].material)].name;
        if (m >= 0 && std::none_of(out.media_absorption.begin(), out.media_absorption.end(),
                                   [&](const auto& e) { return e.first == name; }))
            out.media_absorption.emplace_back(name, R.media[static_cast<size_t>(m)].absorption);
    }
    const std::size_t pixels =
        static_cast<std::size_t>(R.width) * static_cast<std::size_t>(R.height);
    BatchRunOptions bo;
    bo.tally_size = pixels * RenderLayout::kPerPixel;
    // A batch is 3 x n samples per pixel, n with each channel as the hero: the hero choice is
    // stratified within the batch, so the batches are i.i.d. and their spread is the error of
    // this stratified estimator. (With one sample per batch and the hero cycling from batch to
    // batch, the batch statistics would count the differences between heroes as noise and
    // overstate the standard error by up to ~40 % in chromatic media.) Sample budgets are
    // rounded up to a multiple of three; the last batch may be smaller.
    int batch_spp = render_batch_spp(o);
    if (!o.checkpoint_path.empty()) {
        bo.fingerprint = fingerprint_with_batch(scene, o, batch_spp);
        // A resumed render keeps the batch size it started with, whatever the budget now says.
        if (const auto before = !o.fresh && o.batch_spp == 0
                                    ? batch_checkpoint_fingerprint(o.checkpoint_path)
                                    : std::nullopt;
            before && *before != bo.fingerprint)
            for (int b = 3; b <= kMaxBatchSpp; b *= 2)
                if (fingerprint_with_batch(scene, o, b) == *before) {
                    batch_spp = b;
                    bo.fingerprint = *before;
                    break;
                }
        out.content_key = hash_hex(bo.fingerprint);
    }
    bo.batch_samples = batch_spp;
    out.batch_spp = batch_spp;
    bo.budget = o.budget;
    if (!bo.budget.any()) bo.budget.samples = 64;
    if (bo.budget.samples) bo.budget.samples = (*bo.budget.samples + 2) / 3 * 3;
    o.apply(bo);
    bo.checkpoint_path = o.checkpoint_path;
    bo.on_batch = o.on_batch;
    bo.on_resume = o.on_resume;
    bo.quantity = [pixels, measure = o.error_measure](const BatchAccumulator& acc, double& value,
                                                      double& se) {
        auto mean = [&](std::size_t i) { return acc.mean(radiance_element(i)); };
        auto error = [&](std::size_t i) { return acc.standard_error(radiance_element(i)); };
        // A relative error: value 1 with that "standard error", so that the driver's test
        // se <= rel_error * value reads error <= rel_error.
        const RelativeError r = relative_error(3 * pixels, mean, error);
        value = 1.0;
        se = measure == RenderErrorMeasure::kImageMean ? r.mean : r.median;
    };
    const std::uint64_t seed = o.seed;
    const bool sobol = o.sampler == RenderSampler::kSobol;
    out.run = run_batches(
        bo, [&R, seed, pixels, sobol](std::uint64_t index, std::int64_t samples, double* tally) {
            RngStream rng(seed, kRenderDomain, index);
            std::uint64_t rays = 0;
            if (!sobol) {
                for (std::size_t i = 0; i < pixels; ++i) {
                    const int x = static_cast<int>(i % static_cast<std::size_t>(R.width));
                    const int y = static_cast<int>(i / static_cast<std::size_t>(R.width));
                    for (std::int64_t k = 0; k < samples; ++k) {
                        const int hero = static_cast<int>((i + static_cast<std::size_t>(k)) % 3);
                        rays += R.trace(x, y, hero, rng, tally + i * RenderLayout::kPerPixel);
                    }
                }
                return rays;
            }
            // Per pixel and hero, samples/3 points of kSobolPairs independently scrambled pairs of
            // Sobol dimensions, the scrambles seeded from this batch's stream.
            const std::uint64_t key = rng.next_u64();
            const auto key_lo = static_cast<std::uint32_t>(key),
                       key_hi = static_cast<std::uint32_t>(key >> 32);
            const auto per_hero = static_cast<std::uint32_t>(samples / 3);
            std::array<double, 2 * kSobolPairs> prefix{};
            std::array<ScrambledSobol2D, kSobolPairs> pairs;  // per pixel and hero
            for (std::size_t i = 0; i < pixels; ++i) {
                const int x = static_cast<int>(i % static_cast<std::size_t>(R.width));
                const int y = static_cast<int>(i / static_cast<std::size_t>(R.width));
                for (int h = 0; h < 3; ++h) {
                    const int hero = static_cast<int>((i + static_cast<std::size_t>(h)) % 3);
                    const std::uint32_t ph =
                        hash32(hash32(static_cast<std::uint32_t>(i) ^ key_lo) +
                               static_cast<std::uint32_t>(h) * 0x9e3779b9u + key_hi);
                    for (int j = 0; j < kSobolPairs; ++j)
                        pairs[static_cast<std::size_t>(j)] = ScrambledSobol2D(
                            hash32(ph ^ (static_cast<std::uint32_t>(j) * 0x85ebca6bu)));
                    for (std::uint32_t q = 0; q < per_hero; ++q) {
                        for (std::size_t j = 0; j < kSobolPairs; ++j)
                            pairs[j].at(q, prefix[2 * j], prefix[2 * j + 1]);
                        rng.set_prefix(prefix.data(), 2 * kSobolPairs);
                        rays += R.trace(x, y, hero, rng, tally + i * RenderLayout::kPerPixel);
                        rng.set_prefix(nullptr, 0);
                    }
                }
            }
            return rays;
        });
    out.seconds = out.run.seconds;
    out.spp = out.run.samples;
    out.rays = out.run.work;
    out.interrupted = out.run.reason == BatchStop::kInterrupted;
    LayeredImage img(R.width, R.height);
    const char* names[3] = {"radiance", "subsurface", "specular"};
    for (int k = 0; k < 3; ++k) {
        ImageLayer& v = img.add_layer(names[k], 3);
        ImageLayer& e = img.add_layer(std::string(names[k]) + ".stderr", 3);
        for (std::size_t i = 0; i < pixels; ++i)
            for (int c = 0; c < 3; ++c) {
                const std::size_t j = i * RenderLayout::kPerPixel + static_cast<size_t>(3 * k + c);
                const int x = static_cast<int>(i % static_cast<std::size_t>(R.width)),
                          y = static_cast<int>(i / static_cast<std::size_t>(R.width));
                v.at(x, y, c) = static_cast<float>(out.run.mean[j]);
                e.at(x, y, c) = static_cast<float>(out.run.se[j]);
            }
    }
    ImageLayer& depth = img.add_layer("depth", 1);
    ImageLayer& normal = img.add_layer("normal", {"X", "Y", "Z"});
    for (std::size_t i = 0; i < pixels; ++i) {
        const int x = static_cast<int>(i % static_cast<std::size_t>(R.width)),
                  y = static_cast<int>(i / static_cast<std::size_t>(R.width));
        depth.at(x, y) =
            static_cast<float>(out.run.mean[i * RenderLayout::kPerPixel + RenderLayout::kDepth]);
        for (int c = 0; c < 3; ++c)
            normal.at(x, y, c) =
                static_cast<float>(out.run.mean[i * RenderLayout::kPerPixel +
                                                RenderLayout::kNormal + static_cast<size_t>(c)]);
    }
    img.metadata()["ssslab.engine"] = kEngineVersion;
    img.metadata()["ssslab.scene"] = scene.name;
    img.metadata()["ssslab.spp"] = std::to_string(out.spp);
    img.metadata()["ssslab.seed"] = std::to_string(o.seed);
    char secs[32];
    std::snprintf(secs, sizeof secs, "%.3f", out.seconds);
    img.metadata()["ssslab.seconds"] = secs;
    out.image = std::move(img);
    return out;
}

std::vector<ConvergencePoint> convergence(const RenderResult& r, const LayeredImage& reference) {
    if (reference.width() != r.width || reference.height() != r.height)
        throw std::invalid_argument("the reference image is " + std::to_string(reference.width()) +
                                    " x " + std::to_string(reference.height()) + ", the render " +
                                    std::to_string(r.width) + " x " + std::to_string(r.height));
    const ImageLayer& ref = reference.layer("radiance");
    const std::size_t pixels =
        static_cast<std::size_t>(r.width) * static_cast<std::size_t>(r.height);
    double norm = 0;
    for (std::size_t i = 0; i < pixels; ++i)
        for (int c = 0; c < 3; ++c) {
            const double v = ref.at(static_cast<int>(i % static_cast<std::size_t>(r.width)),
                                    static_cast<int>(i / static_cast<std::size_t>(r.width)), c);
            norm += v * v;
        }
    if (!(norm > 0)) throw std::invalid_argument("the reference image is black");
    auto error = [&](const std::vector<double>& mean) {
        double e = 0;
        for (std::size_t i = 0; i < pixels; ++i)
            for (int c = 0; c < 3; ++c) {
                const double v = ref.at(static_cast<int>(i % static_cast<std::size_t>(r.width)),
                                        static_cast<int>(i / static_cast<std::size_t>(r.width)), c);
                const double d = mean[i * RenderLayout::kPerPixel + static_cast<size_t>(c)] - v;
                e += d * d;
            }
        return std::sqrt(e / norm);
    };
    std::vector<ConvergencePoint> out;
    for (const BatchSnapshot& s : r.run.snapshots)
        if (s.samples < r.run.samples) out.push_back({s.samples, s.seconds, error(s.mean), 0});
    double se2 = 0;
    for (std::size_t i = 0; i < pixels; ++i)
        for (int c = 0; c < 3; ++c) {
            const double e = r.run.se[i * RenderLayout::kPerPixel + static_cast<size_t>(c)];
            se2 += e * e;
        }
    out.push_back({r.run.samples, r.run.seconds, error(r.run.mean), std::sqrt(se2 / norm)});
    return out;
}

}  // namespace ssslab::volpath
