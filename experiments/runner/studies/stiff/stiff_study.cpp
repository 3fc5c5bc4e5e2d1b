#include "experiments/runner/studies/stiff/stiff_study.h"

#include "approx/convolve.h"
#include "approx/diffusion.h"
#include "approx/kernel2d.h"
#include "approx/model_spec.h"
#include "approx/separable.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/format.h"
#include "core/material.h"
#include "core/profile.h"
#include "core/scene.h"
#include "core/stats.h"
#include "experiments/runner/nodes.h"
#include "experiments/runner/report.h"
#include "mcml/engine.h"
#include "mcml/run_spec.h"
#include "realtime/sss_pass.h"
#include "volpath/pencil.h"
#include "volpath/render.h"
#include "volpath/sphere.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <map>
#include <sstream>

namespace ssslab::runner {

namespace fs = std::filesystem;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// How a row's estimate is judged.
enum class Test {
    kEqual,     // |estimate - expected| <= z sqrt(se^2 + expected_se^2) + allowance
    kAtMost,    // estimate - expected <= z sqrt(se^2 + expected_se^2) + allowance
    kInterval,  // expected <= estimate <= upper (deterministic bounds, allowance slack)
    kNone,      // finiteness and ending only
};

struct Row {
    std::string engine, axis, value, quantity;
    double estimate = kNaN, se = 0, expected = kNaN, expected_se = 0, allowance = 0;
    double upper = kNaN;  // kInterval's upper end
    Test test = Test::kNone;
    bool stochastic = false;  // the z-test applies (a Monte Carlo estimate)
    long nonfinite = 0;
    long out_of_range = 0;  // values outside their physical range (a negative R_d)
    double seconds = 0;
    bool ended = true;
    bool refused = false;
    std::string note;
    // Filled by judge().
    double z = 0;
    bool pass = true;
};

// Counts the non-finite values of a range.
template <class Range>
long count_nonfinite(const Range& v) {
    long n = 0;
    for (const auto x : v)
        if (!std::isfinite(static_cast<double>(x))) ++n;
    return n;
}

// ---- The media ------------------------------------------------------------------------------

struct Case {
    std::string axis, value;
    Medium medium;
    double albedo = 0.9;
    double scale = 1;  // every length times this (the base is scale 1)
};

Medium grey(double sigma_s, double sigma_a, double g, double eta, double thickness_cm) {
    Medium m;
    m.name = "stiff";
    m.sigma_s_per_cm = {sigma_s, sigma_s, sigma_s};
    m.sigma_a_per_cm = {sigma_a, sigma_a, sigma_a};
    m.g = {g, g, g};
    m.eta = eta;
    m.thickness_cm = thickness_cm;
    return m;
}

constexpr double kBaseSigmaT = 10, kBaseAlbedo = 0.9, kBaseG = 0.8, kBaseEta = 1.4,
                 kBaseThickness = 0.2;

Case make_case(const std::string& axis, const std::string& value, double albedo, double g,
               double eta, double thickness, double scale) {
    Case c;
    c.axis = axis;
    c.value = value;
    c.albedo = albedo;
    c.scale = scale;
    c.medium = grey(kBaseSigmaT * albedo / scale, kBaseSigmaT * (1 - albedo) / scale, g, eta,
                    thickness * scale);
    return c;
}

std::vector<Case> media_cases() {
    std::vector<Case> v;
    v.push_back(make_case("base", "-", kBaseAlbedo, kBaseG, kBaseEta, kBaseThickness, 1));
    const std::vector<std::pair<double, std::string>> albedos = {
        {1e-6, "1e-6"}, {1e-3, "1e-3"},       {0.5, "0.5"},
        {0.99, "0.99"}, {1 - 1e-6, "1-1e-6"}, {1 - 1e-9, "1-1e-9"}};
    for (const auto& [a, s] : albedos)
        v.push_back(make_case("albedo", s, a, kBaseG, kBaseEta, kBaseThickness, 1));
    v.push_back(
        make_case("albedo", "1-1e-6, half-space 1e5 cm", 1 - 1e-6, kBaseG, kBaseEta, 1e5, 1));
    for (double g : {-0.999999, -0.99, 0.0, 0.99, 0.999999})
        v.push_back(make_case("g", format_g(g, 6), kBaseAlbedo, g, kBaseEta, kBaseThickness, 1));
    for (double eta : {0.5, 0.8, 1.0, 1.33, 2.0, 2.5})
        v.push_back(
            make_case("eta", format_g(eta, 6), kBaseAlbedo, kBaseG, eta, kBaseThickness, 1));
    for (double s : {1e-7, 1e-3, 1e3, 1e5})
        v.push_back(
            make_case("scale", format_g(s, 6), kBaseAlbedo, kBaseG, kBaseEta, kBaseThickness, s));
    for (double t : {1e-7, 1e-3, 1e5})
        v.push_back(
            make_case("thickness", format_g(t, 6) + " cm", kBaseAlbedo, kBaseG, kBaseEta, t, 1));
    return v;
}

// ---- Runs -----------------------------------------------------------------------------------

struct Sweep {
    const StiffStudySpec& spec;
    const RenderStudyContext& ctx;
    std::int64_t photons = 0, spp = 0;
    std::vector<Row> rows;
    bool interrupted = false;

    // 32 batches at least (MCML's own rule below 32000 photons), so that the batch-means
    // standard errors are meaningful.
    static std::int64_t batch(std::int64_t samples) {
        return std::max<std::int64_t>(1, samples / 32);
    }
    // The run control of every Monte Carlo run: the study's seed, threads and cancel flag, the
    // budget `samples` with the time cap.
    void control(RunControl& o, std::int64_t samples) const {
        o.seed = ctx.seed;
        o.threads = ctx.threads;
        o.cancel = ctx.cancel;
        o.budget = budget(samples);
    }
    SampleBudget budget(std::int64_t samples) const {
        SampleBudget b;
        b.samples = samples;
        b.seconds = spec.seconds_cap;
        return b;
    }
    // Fills the run-control part of a row; false if the sweep was interrupted.
    bool ended(Row& r, BatchStop reason, double seconds) {
        r.seconds = seconds;
        if (reason == BatchStop::kInterrupted) {
            interrupted = true;
            return false;
        }
        r.ended = reason == BatchStop::kSamples;
        if (!r.ended) r.note = "stopped by the time cap, not by its budget";
        return true;
    }
    void refused(const std::string& engine, const Case& c, const std::string& what) {
        Row r;
        r.engine = engine;
        r.axis = c.axis;
        r.value = c.value;
        r.quantity = "refused";
        r.refused = true;
        r.note = what;
        rows.push_back(r);
    }
    // Runs `f`, turning a refusal into a row.
    void guarded(const std::string& engine, const Case& c, const std::function<void()>& f) {
        try {
            f();
        } catch (const std::invalid_argument& e) {
            refused(engine, c, e.what());
        } catch (const InfeasibleError& e) {
            refused(engine, c, e.what());
        } catch (const InputError& e) {
            refused(engine, c, e.what());
        }
    }
};

Row row(const std::string& engine, const Case& c, const std::string& quantity) {
    Row r;
    r.engine = engine;
    r.axis = c.axis;
    r.value = c.value;
    r.quantity = quantity;
    return r;
}

struct McmlOut {
    double rd = kNaN, rd_se = 0, tt = kNaN, tt_se = 0;
    bool ok = false;
};

// The profile grid of a case: 50 bins over 5 reduced mean free paths (or the thickness, if
// smaller); the volpath grid is the same.
double bin_width_cm(const Case& c) {
    const Medium& m = c.medium;
    const double mfp = 1.0 / (m.sigma_a_per_cm[0] + m.sigma_s_per_cm[0] * (1 - m.g[0]));
    return std::min(5 * mfp, std::max(m.thickness_cm, 1e-300)) / 50;
}

McmlOut run_mcml(Sweep& s, const Case& c) {
    McmlOut out;
    s.guarded("mcml", c, [&] {
        mcml::Grid grid;
        grid.dr = bin_width_cm(c);
        grid.nr = 50;
        grid.dz = c.medium.thickness_cm;
        grid.nz = 1;
        grid.na = 1;
        mcml::RunSpec run = mcml::run_for_channel(c.medium, 0, s.photons, grid);
        mcml::check_run(run, false);
        mcml::EngineOptions o;
        s.control(o, s.photons);
        o.mode = mcml::TallyMode::kProfile;
        const mcml::RunResult r = mcml::run_default(run, o);
        Row e = row("mcml", c, "Rsp + Rd + A + Tt");
        if (!s.ended(e, r.reason, r.seconds)) return;
        e.nonfinite = count_nonfinite(r.values) + count_nonfinite(r.se);
        const auto& l = r.layout;
        e.estimate = r.rsp + r.mean(l.energy);
        e.se = r.se[l.energy];
        e.expected = 1;
        e.allowance = 1e-12;  // conservation is exact per photon but for rounding
        e.test = Test::kEqual;
        e.stochastic = true;
        s.rows.push_back(e);
        out.rd = r.mean(l.rd);
        out.rd_se = r.se[l.rd];
        out.tt = r.mean(l.tt);
        out.tt_se = r.se[l.tt];
        out.ok = true;
    });
    return out;
}

void run_pencil(Sweep& s, const Case& c, const McmlOut& ref) {
    s.guarded("pencil", c, [&] {
        volpath::PencilGrid grid{bin_width_cm(c), 50};
        volpath::check_pencil(c.medium, grid);
        volpath::PencilOptions o;
        s.control(o, s.photons);
        o.only_channel = 0;
        o.batch_paths = s.batch(s.photons);
        const volpath::PencilRun r = volpath::simulate_pencil(c.medium, grid, o);
        const BatchRunResult& b = r.runs[0];
        Row rd = row("pencil", c, "Rd (against MCML)");
        if (!s.ended(rd, r.interrupted ? BatchStop::kInterrupted : b.reason, r.seconds)) return;
        rd.nonfinite = count_nonfinite(b.mean) + count_nonfinite(b.se);
        Row tt = rd;
        tt.quantity = "Tt (against MCML)";
        rd.estimate = r.profile.rd_total[0];
        rd.se = r.profile.rd_total_se[0];
        tt.estimate = r.tt[0];
        tt.se = r.tt_se[0];
        rd.expected = ref.rd;
        rd.expected_se = ref.rd_se;
        tt.expected = ref.tt;
        tt.expected_se = ref.tt_se;
        for (Row* x : {&rd, &tt}) {
            x->allowance = r.lost[0];
            x->test = ref.ok ? Test::kEqual : Test::kNone;
            x->stochastic = true;
            if (r.lost[0] > 0) x->note = "allowance: the mass at risk in the long-path roulette";
            s.rows.push_back(*x);
        }
    });
}

void run_sphere(Sweep& s, const Case& c) {
    s.guarded("sphere", c, [&] {
        volpath::SphereScene scene;
        scene.medium = c.medium;
        scene.radius_cm = c.medium.thickness_cm;
        volpath::check_sphere(scene, false, volpath::ChromaticMode::kHero);
        volpath::SphereOptions o;
        s.control(o, s.photons);
        o.mode = volpath::ChromaticMode::kHero;
        o.image = false;
        o.batch_paths = s.batch(s.photons);
        const volpath::SphereRun r = volpath::simulate_sphere(scene, o);
        const BatchRunResult& b = r.runs[0];
        Row spec = row("sphere", c, "first-surface reflection");
        if (!s.ended(spec, r.interrupted ? BatchStop::kInterrupted : b.reason, r.seconds)) return;
        spec.nonfinite = count_nonfinite(b.mean) + count_nonfinite(b.se);
        Row total = spec;
        spec.estimate = r.specular[0];
        spec.se = r.specular_se[0];
        spec.expected = r.specular_expected;  // by quadrature, not by the walk
        spec.test = Test::kEqual;
        spec.stochastic = true;
        s.rows.push_back(spec);
        // diffuse + specular, tallied separately: the SE of the sum is at most the sum of SEs.
        total.quantity = "diffuse + specular";
        total.estimate = r.diffuse[0] + r.specular[0];
        total.se = r.diffuse_se[0] + r.specular_se[0];
        total.expected = 1;
        total.stochastic = true;
        const double events = static_cast<double>(r.events) / std::max<double>(1, r.paths);
        if (c.albedo >= 1 - 1e-6) {
            total.test = Test::kEqual;
            total.allowance = (1 - c.albedo) * events + r.lost[0];
            total.note = "white: equal to 1 up to (1 - albedo) x events per photon + mass at risk";
        } else {
            total.test = Test::kAtMost;
        }
        s.rows.push_back(total);
    });
}

// A furnace: the sphere of the case (radius 1.5 mm x scale, its coefficients per mm) under a
// constant environment of radiance 1, 16 x 16 pixels.
void run_render(Sweep& s, const Case& c) {
    s.guarded("render", c, [&] {
        const Medium& m = c.medium;
        // The case's lengths are in cm for a 0.2 cm base; the scene's sphere is 1.5 mm across the
        // base, so its coefficients per mm keep the base's optical radius (3 mfp).
        const double k = kBaseThickness * 10 / 1.5;  // per cm -> per mm at the scene's size
        std::ostringstream t;
        t.precision(17);
        const double sc = c.scale;
        t << "[scene]\nname = \"furnace\"\n[camera]\nposition = [0, 0, " << 10 * sc
          << "]\ntarget = [0, 0, 0]\nfov_y_deg = 30\nwidth = 16\nheight = 16\n"
          << "[[lights]]\ntype = \"environment\"\nradiance = 1\n"
          << "[[materials]]\nname = \"m\"\nsigma_a_per_mm = " << m.sigma_a_per_cm[0] * k
          << "\nsigma_s_per_mm = " << m.sigma_s_per_cm[0] * k << "\ng = " << m.g[0]
          << "\neta = " << m.eta << "\n[[shapes]]\ntype = \"sphere\"\nradius = " << 1.5 * sc
          << "\nsubdivisions = 3\nmaterial = \"m\"\n";
        const Scene scene = parse_scene(t.str(), "stiff-furnace.toml", ".");
        volpath::check_renderable(scene);
        volpath::RenderOptions o;
        s.control(o, s.spp);
        o.batch_spp = 3;  // spp / 3 batches (>= 32): their spread is the error
        const volpath::RenderResult r = volpath::render(scene, o);
        Row e = row("render", c, "furnace image mean over the sphere");
        if (!s.ended(e, r.interrupted ? BatchStop::kInterrupted : r.run.reason, r.seconds)) return;
        for (const auto& layer : r.image.layers()) e.nonfinite += count_nonfinite(layer.pixels());
        const ImageLayer& L = r.image.layer("radiance");
        const ImageLayer& E = r.image.layer("radiance.stderr");
        double sum = 0, var = 0;
        long n = 0;
        for (int y = 0; y < r.height; ++y)
            for (int x = 0; x < r.width; ++x)
                for (int ch = 0; ch < 3; ++ch)
                    if (E.at(x, y, ch) > 0) {
                        sum += L.at(x, y, ch);
                        var += static_cast<double>(E.at(x, y, ch)) * E.at(x, y, ch);
                        ++n;
                    }
        if (n == 0) {
            e.note = "no pixel saw the medium";
            e.test = Test::kNone;
            s.rows.push_back(e);
            return;
        }
        // Pixels are independent paths: the SE of their mean is sqrt(sum se^2) / n.
        e.estimate = sum / n;
        e.se = std::sqrt(var) / n;
        e.expected = 1;
        e.stochastic = true;
        const double queries =
            static_cast<double>(r.rays) / (static_cast<double>(r.width * r.height) * r.spp);
        if (c.albedo >= 1 - 1e-6) {
            e.test = Test::kEqual;
            e.allowance = (1 - c.albedo) * queries;
            e.note = "white: equal to 1 up to (1 - albedo) x queries per path";
        } else {
            e.test = Test::kAtMost;
        }
        s.rows.push_back(e);
    });
}

// Every analytic profile on the case's medium (lengths in cm).
void run_diffusion(Sweep& s, const Case& c) {
    const Medium& m = c.medium;
    const approx::DiffusionMedium d = approx::diffusion_medium(m, 0);
    for (const std::string& name : approx::diffusion_model_names()) {
        s.guarded("diffusion " + name, c, [&] {
            const auto t0 = std::chrono::steady_clock::now();
            const auto p = approx::make_diffusion_profile(name, d);
            const double mfp = 1.0 / d.sigma_t_reduced();
            Row r = row("diffusion " + name, c, "2 pi int R_d r dr = R_dr");
            for (int i = 0; i <= 100; ++i) {
                const double rr = mfp * std::pow(10.0, -6 + 0.1 * i);
                const double v = p->rd(rr);
                if (!std::isfinite(v)) ++r.nonfinite;
                if (v < 0) ++r.out_of_range;
            }
            const double total = p->total_rd();
            if (!std::isfinite(total)) ++r.nonfinite;
            // 2 pi int R_d r dr by Simpson's rule in ln r over [1e-10, 1e6] reduced mean free
            // paths, 40 points per e-fold (not the model's own quadrature, annulus_mean); the
            // classical dipole at albedo 1 falls as 1/r^3, so beyond 1e6 lies ~1e-6 of R_dr.
            const double lo = std::log(1e-10 * mfp), hi = std::log(1e6 * mfp);
            const int n = 2 * static_cast<int>(std::ceil(20 * (hi - lo)));
            const double h = (hi - lo) / n;
            double integral = 0;
            for (int i = 0; i <= n; ++i) {
                const double rr = std::exp(lo + i * h);
                const double w = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
                integral += w * rr * rr * p->rd(rr);
            }
            integral *= 2 * 3.141592653589793 * h / 3;
            // Below r0 = 1e-10 mfp: R_d ~ C / r at most (DiffusionProfile::rd), so the disc holds
            // 2 pi C r0 = 2 pi r0^2 R_d(r0) (PBD's single scattering at g = -0.999999 puts 5e-5
            // of R_dr there).
            const double r0 = std::exp(lo);
            integral += 2 * 3.141592653589793 * r0 * r0 * p->rd(r0);
            r.estimate = integral;
            r.expected = total;
            r.allowance = 1e-5 * std::fabs(total) + 1e-15;
            r.test = Test::kEqual;
            r.seconds =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            if (r.out_of_range) r.note = "negative values of R_d";
            s.rows.push_back(r);
            Row b = row("diffusion " + name, c, "0 <= R_dr <= 1");
            b.estimate = total;
            b.expected = 0;
            b.upper = 1;
            b.allowance = 1e-12;
            b.test = Test::kInterval;
            s.rows.push_back(b);
        });
    }
}

// The separable models on a dipole kernel whose extent is `width` pixels (a 64 x 64 image):
// the constant image stays equal to the kernel's mass under the full-resolution passes and
// under the SSS pass's taps.
void run_kernels(Sweep& s) {
    const std::vector<std::string> specs = {"svd:rank=1",         "svd:rank=3,l1",
                                            "preintegration",     "guided:k=1",
                                            "guided:k=1.55,b=50", "manual:near=0.1,far=0.8,w=0.5",
                                            "deon:n=3",           "ssss_skin"};
    // Skin-like dipole, binned as MCML bins (the area average over each annulus).
    approx::DiffusionMedium d;
    d.sigma_a = 0.15;  // per mm
    d.sigma_s = 10;
    d.g = 0.8;
    d.eta = 1.4;
    const auto dip = approx::make_diffusion_profile("dipole", d);
    RadialProfile prof;
    prof.name = "stiff-dipole";
    const double dr_mm = 0.02;
    prof.dr_cm = dr_mm / 10;
    prof.nr = 200;
    for (int ch = 0; ch < 3; ++ch) {
        prof.rd_per_cm2[ch].resize(200);
        prof.se_per_cm2[ch].assign(200, 0.0);
        for (int i = 0; i < 200; ++i)
            prof.rd_per_cm2[ch][static_cast<size_t>(i)] =
                100 * dip->annulus_mean(i * dr_mm, (i + 1) * dr_mm);
    }
    const approx::KernelGrid grid = approx::KernelGrid::from_profile(prof);
    std::array<std::unique_ptr<approx::Kernel2D>, 3> k;
    for (int ch = 0; ch < 3; ++ch)
        k[static_cast<size_t>(ch)] = std::make_unique<approx::Kernel2D>(prof, ch, grid);
    const int size = 64;
    const std::vector<std::pair<double, std::string>> widths = {
        {1e-4, "1e-4 px"}, {0.3, "0.3 px"}, {8, "8 px"}, {200, "3 images"}, {6.4e5, "1e4 images"}};
    for (const std::string& text : specs) {
        const approx::ModelSpec spec = approx::parse_model(text);
        approx::ModelContext ctx;
        ctx.material = "Skin1";
        std::array<approx::ModelResult, 3> res;
        Case c;
        c.axis = "kernel width";
        bool ok = true;
        for (int ch = 0; ch < 3 && ok; ++ch) {
            ctx.channel = ch;
            try {
                res[static_cast<size_t>(ch)] =
                    approx::build_model(spec, *k[static_cast<size_t>(ch)], ctx);
            } catch (const std::invalid_argument& e) {
                c.value = "all";
                s.refused("kernel " + spec.label(), c, e.what());
                ok = false;
            }
        }
        if (!ok) continue;
        const std::array<const approx::SeparableKernel*, 3> a = {&res[0].kernel, &res[1].kernel,
                                                                 &res[2].kernel};
        for (const auto& [w, label] : widths) {
            c.value = label;
            const double pixel_mm = grid.extent_mm() * 2 / w;
            const auto t0 = std::chrono::steady_clock::now();
            Row r = row("kernel " + spec.label(), c, "constant image, separable passes");
            Row t = row("SSS pass " + spec.label(), c, "constant G-buffer, taps");
            approx::ImageRGB one(size, size, pixel_mm, 1.0);
            const approx::ImageRGB out = approx::convolve_separable(one, a);
            double worst = 0;
            for (int ch = 0; ch < 3; ++ch) {
                const double mass = a[static_cast<size_t>(ch)]->sum();
                r.nonfinite += count_nonfinite(out.c[static_cast<size_t>(ch)]);
                for (double v : out.c[static_cast<size_t>(ch)])
                    worst = std::max(worst, std::fabs(v - mass));
            }
            r.estimate = worst;
            r.expected = 0;
            r.allowance = 1e-9;
            r.test = Test::kEqual;
            r.seconds =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            r.note = "estimate: the largest |output - kernel mass| over the pixels";
            s.rows.push_back(r);
            // The SSS pass: view depth 1, tan(fov/2) 1, so a pixel is 2 / size world units.
            const auto t1 = std::chrono::steady_clock::now();
            const realtime::SssMaterialKernel mk = realtime::make_material_kernel(a, 17);
            realtime::SssGBuffer g(size, size);
            std::fill(g.irradiance.begin(), g.irradiance.end(), 1.0f);
            realtime::SssParams p;
            p.unit_mm = pixel_mm * size / 2;
            const std::vector<float> o = realtime::sss_pass(g, {mk}, p);
            t.nonfinite = count_nonfinite(o);
            double tw = 0;  // the largest gap between the pass and its taps' mass, and between
            double tm = 0;  // the taps' mass and the kernel's
            for (int ch = 0; ch < 3; ++ch) {
                double taps_mass = 0;
                for (const auto& term : mk.terms) {
                    double sw = 0;
                    for (double v : term.taps.weight[static_cast<size_t>(ch)]) sw += v;
                    taps_mass += term.sign[static_cast<size_t>(ch)] * sw * sw;
                }
                tm = std::max(tm, std::fabs(taps_mass - a[static_cast<size_t>(ch)]->sum()));
                for (size_t i = static_cast<size_t>(ch); i < o.size(); i += 3)
                    tw = std::max(tw, std::fabs(o[i] - taps_mass));
            }
            t.estimate = tw;
            t.expected = 0;
            t.allowance = 1e-5;  // the pass works in float
            t.test = Test::kEqual;
            t.seconds =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
            t.note = "estimate: the largest |output - taps' mass|";
            s.rows.push_back(t);
            Row m = row("SSS pass " + spec.label(), c, "taps' mass = kernel mass");
            m.estimate = tm;
            m.expected = 0;
            m.allowance = 1e-9;
            m.test = Test::kEqual;
            m.note = "estimate: the largest |taps' mass - kernel mass| over the channels";
            s.rows.push_back(m);
        }
    }
}

// ---- Judging and the tables -----------------------------------------------------------------

void judge(std::vector<Row>& rows, double alpha) {
    int tests = 0;
    for (const Row& r : rows)
        if (r.stochastic && r.test != Test::kNone) ++tests;
    const double zc = normal_quantile(1 - sidak(alpha, tests) / 2);
    for (Row& r : rows) {
        if (r.refused) continue;
        bool ok = r.nonfinite == 0 && r.out_of_range == 0 && r.ended;
        const double sd = std::sqrt(r.se * r.se + r.expected_se * r.expected_se);
        const double d = r.estimate - r.expected;
        const double slack = (r.stochastic ? zc * sd : 0.0) + r.allowance;
        switch (r.test) {
            case Test::kEqual:
                ok = ok && std::fabs(d) <= slack;
                break;
            case Test::kAtMost:
                ok = ok && d <= slack;
                break;
            case Test::kInterval:
                ok = ok && r.estimate >= r.expected - r.allowance &&
                     r.estimate <= r.upper + r.allowance;
                break;
            case Test::kNone:
                break;
        }
        if (!std::isfinite(r.estimate) && r.test != Test::kNone) ok = false;
        r.z = r.stochastic && sd > 0 ? d / sd : 0;
        r.pass = ok;
    }
}

const char* test_name(Test t) {
    switch (t) {
        case Test::kEqual:
            return "equal";
        case Test::kAtMost:
            return "at most";
        case Test::kInterval:
            return "in [expected, upper]";
        case Test::kNone:
            return "finite, ended";
    }
    return "";
}

std::string sweep_csv(const std::vector<Row>& rows) {
    std::ostringstream os;
    os << "engine,axis,value,quantity,test,estimate,se,expected,expected_se,upper,allowance,z,"
          "nonfinite,out_of_range,seconds,ended,refused,pass,note\n";
    for (const Row& r : rows)
        os << csv_field(r.engine) << "," << csv_field(r.axis) << "," << csv_field(r.value) << ","
           << csv_field(r.quantity) << "," << csv_field(test_name(r.test)) << ","
           << format_g(r.estimate, 10) << "," << format_g(r.se, 4) << ","
           << format_g(r.expected, 10) << "," << format_g(r.expected_se, 4) << ","
           << format_g(r.upper, 4) << "," << format_g(r.allowance, 3) << "," << format_g(r.z, 3)
           << "," << r.nonfinite << "," << r.out_of_range << "," << format_g(r.seconds, 3) << ","
           << (r.ended ? 1 : 0) << "," << (r.refused ? 1 : 0) << "," << (r.pass ? 1 : 0) << ","
           << csv_field(r.note) << "\n";
    return os.str();
}

struct Summary {
    int checks = 0, passed = 0, refused = 0;
    long nonfinite = 0;
    double worst_z = 0, longest = 0;
};

// Per engine family ("diffusion dipole" -> "diffusion", "kernel svd1" -> "kernel") and axis.
std::string family(const std::string& engine) {
    return engine.substr(0,
                         engine.find(' ') == std::string::npos ? engine.size() : engine.find(' '));
}

}  // namespace

StiffStudySpec read_stiff_study(ConfigTable& t) {
    StiffStudySpec s;
    s.enabled = true;
    s.photons = t.integer("photons", s.photons, Range::closed(100, 1e9));
    s.spp = t.integer("spp", s.spp, Range::closed(96, 1e6));
    s.seconds_cap = t.number("seconds_cap", s.seconds_cap, Range::left_open(0, 1e6));
    s.quick_factor = t.number("quick_factor", s.quick_factor, Range::left_open(0, 1));
    s.alpha = t.number("alpha", s.alpha, Range::open(0, 1));
    return s;
}

StudyResult run_stiff_study(const StiffStudySpec& spec, const RenderStudyContext& ctx) {
    Sweep s{spec, ctx, 0, 0, {}, false};
    s.photons = spec.photons;
    s.spp = spec.spp;
    if (ctx.quick) {
        s.photons = std::max<std::int64_t>(
            1000, static_cast<std::int64_t>(std::llround(spec.photons * spec.quick_factor)));
        s.spp = std::max<std::int64_t>(
            96, static_cast<std::int64_t>(std::llround(spec.spp * spec.quick_factor)));
    }
    StudyResult res;
    int checks = 0, failed = 0, refused = 0;
    std::vector<Metric>& metrics = res.metrics;
    const std::vector<Case> cases = media_cases();
    McmlOut base;  // the base case's MCML result, for the scale axis
    for (const Case& c : cases) {
        if (!ctx.quiet) std::printf("  stiff sweep: %s %s\n", c.axis.c_str(), c.value.c_str());
        const McmlOut m = run_mcml(s, c);
        if (s.interrupted) break;
        if (c.axis == "base") base = m;
        if (c.axis == "scale" && m.ok && base.ok) {
            auto against_base = [&](const char* quantity, double v, double se, double b,
                                    double b_se) {
                Row r = row("mcml", c, quantity);
                r.estimate = v;
                r.se = se;
                r.expected = b;
                r.expected_se = b_se;
                r.test = Test::kEqual;
                r.stochastic = true;
                s.rows.push_back(r);
            };
            against_base("Rd (against scale 1)", m.rd, m.rd_se, base.rd, base.rd_se);
            against_base("Tt (against scale 1)", m.tt, m.tt_se, base.tt, base.tt_se);
        }
        run_pencil(s, c, m);
        if (s.interrupted) break;
        run_sphere(s, c);
        if (s.interrupted) break;
        run_diffusion(s, c);
        // The renders: the axes that change the sphere's optics (not the slab's thickness).
        if (c.axis != "thickness" && c.value.find("half-space") == std::string::npos) {
            Case rc = c;
            if (c.axis == "scale") rc.scale = c.scale < 1 ? 1e-6 : 1e6;
            run_render(s, rc);
            if (s.interrupted) break;
        }
    }
    if (s.interrupted) {
        res.interrupted = true;
        return res;
    }
    run_kernels(s);
    judge(s.rows, spec.alpha);

    std::map<std::pair<std::string, std::string>, Summary> sums;
    std::map<std::string, int> failed_by_family;
    for (const Row& r : s.rows) {
        Summary& x = sums[{family(r.engine), r.axis}];
        ++x.checks;
        ++checks;
        if (r.refused) {
            ++x.refused;
            ++refused;
            continue;
        }
        failed_by_family[family(r.engine)] += r.pass ? 0 : 1;
        if (r.pass)
            ++x.passed;
        else
            ++failed;
        x.nonfinite += r.nonfinite;
        if (r.test == Test::kEqual) x.worst_z = std::max(x.worst_z, std::fabs(r.z));
        x.longest = std::max(x.longest, r.seconds);
    }
    std::ostringstream sum;
    sum << "engine,axis,checks,passed,refused,nonfinite,worst_abs_z,longest_seconds\n";
    for (const auto& [k, x] : sums)
        sum << k.first << "," << k.second << "," << x.checks << "," << x.passed << "," << x.refused
            << "," << x.nonfinite << "," << format_g(x.worst_z, 3) << "," << format_g(x.longest, 3)
            << "\n";
    const std::string sweep = sweep_csv(s.rows);
    res.files["sweep.csv"] = sweep;
    res.files["summary.csv"] = sum.str();
    for (const auto& [fam, n] : failed_by_family) {
        Metric m;
        m.name = "stiff." + fam + ".failed";
        m.unit = "checks";
        m.value = n;
        m.stochastic = false;
        m.tolerance = 0;
        metrics.push_back(m);
    }

    StudySection& sec = res.section;
    sec.id = "stiff";
    sec.title = "The stiff sweep";
    sec.paragraphs.push_back(
        "Every engine and model on the extremes of its inputs (albedo 1e-6 to 1 - 1e-9, g to "
        "\u00b10.999999, index ratios 0.5 to 2.5, every length times 1e-7 to 1e5, kernels from "
        "1e-4 pixel to 1e4 images): " +
        std::to_string(checks) + " checks, " + std::to_string(failed) + " failed, " +
        std::to_string(refused) + " refused with a message; " + std::to_string(s.photons) +
        " photons per Monte Carlo run, " + std::to_string(s.spp) +
        " samples per pixel per furnace render. A check passes when nothing it produced is NaN "
        "or Inf, the run ended by its budget (not by the time cap of " +
        format_g(spec.seconds_cap, 6) +
        " s), and its energy agrees with physics (z-tests at family-wise alpha " +
        format_g(spec.alpha, 6) +
        ", Sidak). See the header of experiments/runner/studies/stiff/stiff_study.h for what "
        "each check compares with.");
    sec.tables.push_back({"Per engine and axis (stiff/summary.csv)", sum.str()});
    std::string failing = "engine,axis,value,quantity,estimate,se,expected,z,nonfinite,note\n";
    for (const Row& r : s.rows)
        if (!r.refused && !r.pass)
            failing += r.engine + "," + r.axis + "," + csv_field(r.value) + "," +
                       csv_field(r.quantity) + "," + format_g(r.estimate, 6) + "," +
                       format_g(r.se, 3) + "," + format_g(r.expected, 6) + "," + format_g(r.z, 3) +
                       "," + std::to_string(r.nonfinite) + "," + csv_field(r.note) + "\n";
    if (failed) sec.tables.push_back({"Failed checks", failing});
    std::string refusals = "engine,axis,value,message\n";
    for (const Row& r : s.rows)
        if (r.refused)
            refusals +=
                r.engine + "," + r.axis + "," + csv_field(r.value) + "," + csv_field(r.note) + "\n";
    if (refused) sec.tables.push_back({"Refused inputs", refusals});
    sec.paragraphs.push_back("Every check: stiff/sweep.csv.");
    res.summary = std::to_string(checks) + " checks, " + std::to_string(failed) + " failed, " +
                  std::to_string(refused) + " refused";
    return res;
}

namespace {

class StiffStudy final : public Study {
  public:
    explicit StiffStudy(StiffStudySpec s) : spec_(s) {}
    std::string describe() const override { return "stiff (the sweep, computed when run)"; }
    double quick_factor() const override { return spec_.quick_factor; }
    StudyResult run(const StudyInputs& in) const override { return run_stiff_study(spec_, in.ctx); }

  private:
    StiffStudySpec spec_;
};

std::shared_ptr<const Study> make_stiff_study(ConfigTable& t, const std::string&) {
    return std::make_shared<StiffStudy>(read_stiff_study(t));
}

}  // namespace

}  // namespace ssslab::runner

SSSLAB_REGISTER_STUDY(stiff, ssslab::runner::make_stiff_study)
