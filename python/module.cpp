// The Python module `ssslab` (pybind11): the two Monte Carlo engines' radial profiles, the
// analytic diffusion profiles, the separable kernel models and their scores, scene rendering and
// the experiment runner, returning numpy arrays with their standard errors. Units are in the
// names, as in the C++ API (coefficients per cm, R_d per cm^2). The engines run with the GIL
// released; bad input raises ssslab.InputError (a ValueError) with the same located message the
// command line prints, an infeasible run ssslab.InfeasibleError, a failed write ssslab.IoError.
#include "approx/diffusion.h"
#include "approx/kernel2d.h"
#include "approx/model_spec.h"
#include "approx/separable.h"
#include "core/build_info.h"
#include "core/error.h"
#include "core/film_image.h"
#include "core/material.h"
#include "core/profile.h"
#include "core/scene.h"
#include "experiments/runner/profile_models.h"
#include "experiments/runner/runner.h"
#include "mcml/profile.h"
#include "volpath/pencil.h"
#include "volpath/render.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <optional>
#include <string>
#include <vector>

namespace py = pybind11;

namespace ssslab::python {

namespace {

using Array = py::array_t<double>;

// A (rows, cols) array of the three channels' vectors (each of length cols).
Array channels_2d(const std::array<std::vector<double>, 3>& v) {
    const size_t n = v[0].size();
    Array a({size_t{3}, n});
    auto m = a.mutable_unchecked<2>();
    for (py::ssize_t c = 0; c < 3; ++c)
        for (py::ssize_t i = 0; i < static_cast<py::ssize_t>(n); ++i)
            m(c, i) = v[static_cast<size_t>(c)].size() == n ? v[static_cast<size_t>(c)][i] : NAN;
    return a;
}

Array vec3(const std::array<double, 3>& v) {
    Array a(3);
    auto m = a.mutable_unchecked<1>();
    for (py::ssize_t c = 0; c < 3; ++c) m(c) = v[static_cast<size_t>(c)];
    return a;
}

std::array<double, 3> rgb(const py::object& o, const char* what) {
    if (py::isinstance<py::float_>(o) || py::isinstance<py::int_>(o)) {
        const double x = o.cast<double>();
        return {x, x, x};
    }
    const auto v = o.cast<std::vector<double>>();
    if (v.size() != 3)
        throw std::invalid_argument(std::string(what) +
                                    ": give one number or three (R, G, B), got " +
                                    std::to_string(v.size()));
    return {v[0], v[1], v[2]};
}

// A sample budget from Python: a count (int or float such as 1e6), optional seconds.
SampleBudget budget(std::optional<double> samples, std::optional<double> seconds,
                    const char* what) {
    SampleBudget b;
    if (samples) {
        if (!(*samples >= 1) || *samples > 1e15 || *samples != std::floor(*samples))
            throw std::invalid_argument(std::string(what) + " must be a whole number >= 1, got " +
                                        std::to_string(*samples));
        b.samples = static_cast<std::int64_t>(*samples);
    }
    if (seconds) {
        if (!(*seconds > 0) || !std::isfinite(*seconds))
            throw std::invalid_argument("seconds must be positive, got " +
                                        std::to_string(*seconds));
        b.seconds = *seconds;
    }
    return b;
}

int check_threads(int threads) {
    if (threads < 0) throw std::invalid_argument("threads must be >= 0 (0: all cores)");
    return threads;
}

// The run control every engine call takes: seed, threads, a budget (`fallback` samples if none).
void set_run_control(RunControl& o, std::uint64_t seed, int threads, std::optional<double> samples,
                     std::optional<double> seconds, const char* what, std::int64_t fallback) {
    o.seed = seed;
    o.threads = check_threads(threads);
    o.budget = budget(samples, seconds, what);
    if (!o.budget.any()) o.budget.samples = fallback;
}

int check_channel(int c) {
    if (c < 0 || c > 2) throw std::invalid_argument("channel must be 0, 1 or 2 (R, G, B)");
    return c;
}

// The grid of Freude14 Table 6.1 with the caller's dr_cm / nr over it, as a config's grid keys.
mcml::ProfileGrid grid_of(const Medium& m, std::optional<double> dr_cm, std::optional<int> nr) {
    if (dr_cm && (!(*dr_cm > 0) || !std::isfinite(*dr_cm)))
        throw std::invalid_argument("dr_cm must be positive");
    if (nr && (*nr < 1 || *nr > 100000000)) throw std::invalid_argument("nr must be in [1, 1e8]");
    return mcml::GridOverride{dr_cm, nr}.apply(mcml::freude14_grid(m));
}

// The layers of a rendered image as numpy arrays (height, width, channels).
py::dict image_layers(const LayeredImage& img) {
    py::dict d;
    for (const ImageLayer& l : img.layers()) {
        py::array_t<float> a({static_cast<size_t>(l.height()), static_cast<size_t>(l.width()),
                              static_cast<size_t>(l.channels())});
        const auto px = l.pixels();
        std::copy(px.begin(), px.end(), a.mutable_data());
        d[py::str(l.name())] = a;
    }
    return d;
}

// ssslab.InputError, InfeasibleError and IoError, and the translation of the C++ errors into them.
void bind_errors(py::module_& m) {
    // Bad input carries its location (file:line:column, key, the offending line) in the message.
    static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
    static py::exception<InfeasibleError> infeasible_error(m, "InfeasibleError", PyExc_ValueError);
    static py::exception<IoError> io_error(m, "IoError", PyExc_OSError);
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const InputError& e) {
            input_error(e.what());
        } catch (const InfeasibleError& e) {
            infeasible_error(e.what());
        } catch (const IoError& e) {
            io_error(e.what());
        }
    });
}

// ssslab.Medium and the measured materials.
void bind_media(py::module_& m) {
    // ---- Media --------------------------------------------------------------------------------
    py::class_<Medium>(m, "Medium",
                       "A homogeneous slab per RGB channel: coefficients per cm, Henyey-Greenstein "
                       "g, index of refraction, thickness in cm (1e8: quasi-infinite).")
        .def(py::init([](const py::object& sigma_a_per_cm, const py::object& sigma_s_per_cm,
                         const py::object& g, double eta, double thickness_cm, double eta_above,
                         double eta_below, const std::string& name) {
                 Medium md;
                 md.name = name;
                 md.sigma_a_per_cm = rgb(sigma_a_per_cm, "sigma_a_per_cm");
                 md.sigma_s_per_cm = rgb(sigma_s_per_cm, "sigma_s_per_cm");
                 md.g = rgb(g, "g");
                 md.eta = eta;
                 md.thickness_cm = thickness_cm;
                 md.eta_above = eta_above;
                 md.eta_below = eta_below;
                 for (int c = 0; c < 3; ++c) {
                     if (!(md.sigma_a_per_cm[c] >= 0) || !(md.sigma_s_per_cm[c] >= 0) ||
                         !(md.sigma_a_per_cm[c] + md.sigma_s_per_cm[c] > 0) ||
                         !std::isfinite(md.sigma_a_per_cm[c] + md.sigma_s_per_cm[c]))
                         throw std::invalid_argument(
                             "Medium: sigma_a_per_cm and sigma_s_per_cm must be finite, >= 0, "
                             "with a positive sum");
                     if (!(md.g[c] >= -1 && md.g[c] <= 1))
                         throw std::invalid_argument("Medium: g must be in [-1, 1]");
                 }
                 if (!(eta > 0) || !(eta_above > 0) || !(eta_below > 0) || !std::isfinite(eta) ||
                     !std::isfinite(eta_above) || !std::isfinite(eta_below))
                     throw std::invalid_argument("Medium: indices must be positive and finite");
                 if (!(thickness_cm > 0) || !std::isfinite(thickness_cm))
                     throw std::invalid_argument("Medium: thickness_cm must be positive");
                 return md;
             }),
             py::arg("sigma_a_per_cm"), py::arg("sigma_s_per_cm"), py::arg("g") = 0.0,
             py::arg("eta") = 1.0, py::arg("thickness_cm") = 1e8, py::arg("eta_above") = 1.0,
             py::arg("eta_below") = 1.0, py::arg("name") = "")
        .def_readonly("name", &Medium::name)
        .def_property_readonly("sigma_a_per_cm",
                               [](const Medium& x) { return vec3(x.sigma_a_per_cm); })
        .def_property_readonly("sigma_s_per_cm",
                               [](const Medium& x) { return vec3(x.sigma_s_per_cm); })
        .def_property_readonly("g", [](const Medium& x) { return vec3(x.g); })
        .def_readonly("eta", &Medium::eta)
        .def_readonly("eta_above", &Medium::eta_above)
        .def_readonly("eta_below", &Medium::eta_below)
        .def_readonly("thickness_cm", &Medium::thickness_cm)
        .def_property_readonly("mfp_cm",
                               [](const Medium& x) {
                                   return vec3({x.mfp_cm(0), x.mfp_cm(1), x.mfp_cm(2)});
                               })
        .def("__repr__", [](const Medium& x) {
            return "<ssslab.Medium " + (x.name.empty() ? std::string("(unnamed)") : x.name) +
                   ", eta " + std::to_string(x.eta) + ">";
        });

    m.def(
        "materials",
        [] {
            std::vector<std::string> names;
            for (const auto& p : freude14_materials()) names.push_back(p.name);
            return names;
        },
        "The measured materials of Freude14 Table 6.2 (Jensen et al. 2001).");
    m.def(
        "material",
        [](const std::string& name) {
            const auto md = find_material(name);
            if (!md) throw std::invalid_argument(unknown_material_message(name));
            return *md;
        },
        py::arg("name"), "A measured material by name (case-insensitive), e.g. \"Skin1\".");
}

// ssslab.Profile and read_profile.
void bind_profiles(py::module_& m) {
    // ---- Radial profiles ----------------------------------------------------------------------
    py::class_<RadialProfile>(m, "Profile",
                              "A radial diffuse reflectance profile R_d(r) per RGB channel with "
                              "the standard error of every bin (annuli [i dr, (i+1) dr)).")
        .def_readonly("name", &RadialProfile::name)
        .def_readonly("dr_cm", &RadialProfile::dr_cm)
        .def_readonly("nr", &RadialProfile::nr)
        .def_property_readonly(
            "r_cm",
            [](const RadialProfile& p) {
                Array a(p.nr);
                auto v = a.mutable_unchecked<1>();
                for (py::ssize_t i = 0; i < p.nr; ++i) v(i) = (i + 0.5) * p.dr_cm;
                return a;
            },
            "bin centres [cm]")
        .def_property_readonly(
            "rd_per_cm2", [](const RadialProfile& p) { return channels_2d(p.rd_per_cm2); },
            "(3, nr): mean R_d over each annulus [1/cm^2]")
        .def_property_readonly(
            "se_per_cm2", [](const RadialProfile& p) { return channels_2d(p.se_per_cm2); },
            "(3, nr): its standard error")
        .def_property_readonly("rd_total", [](const RadialProfile& p) { return vec3(p.rd_total); })
        .def_property_readonly("rd_total_se",
                               [](const RadialProfile& p) { return vec3(p.rd_total_se); })
        .def_property_readonly("beyond", [](const RadialProfile& p) { return vec3(p.beyond); })
        .def_property_readonly("beyond_se",
                               [](const RadialProfile& p) { return vec3(p.beyond_se); })
        .def_property_readonly("rsp", [](const RadialProfile& p) { return vec3(p.rsp); })
        .def(
            "to_csv",
            [](const RadialProfile& p, const std::string& unit) {
                if (unit != "mm" && unit != "cm")
                    throw std::invalid_argument("unit: \"mm\" or \"cm\"");
                return p.to_csv(unit == "mm" ? LengthUnit::kMm : LengthUnit::kCm);
            },
            py::arg("unit") = "mm");
    m.def("read_profile", &read_profile_csv, py::arg("path"),
          "A profile from a CSV written by ssslab (either unit).");
}

// The two Monte Carlo engines' pencil beams: mcml_profile, pencil_profile.
void bind_engines(py::module_& m) {
    m.def(
        "mcml_profile",
        [](const Medium& md, std::optional<double> photons, std::optional<double> seconds,
           std::uint64_t seed, int threads, std::optional<double> dr_cm, std::optional<int> nr) {
            mcml::ProfileOptions o;
            set_run_control(o, seed, threads, photons, seconds, "photons", 100000);
            const mcml::ProfileGrid g = grid_of(md, dr_cm, nr);
            mcml::ProfileRun r;
            {
                py::gil_scoped_release release;
                r = mcml::simulate_profile(md, g, o);
            }
            r.profile.name = md.name.empty() ? "mcml" : md.name;
            return r.profile;
        },
        py::arg("medium"), py::arg("photons") = py::none(), py::arg("seconds") = py::none(),
        py::arg("seed") = 1, py::arg("threads") = 0, py::arg("dr_cm") = py::none(),
        py::arg("nr") = py::none(),
        "R_d(r) of a pencil beam at normal incidence by the MCML port, per channel (default "
        "1e5 photons each; the grid of Freude14 Table 6.1 unless dr_cm / nr are given). "
        "Deterministic for any thread count.");

    m.def(
        "pencil_profile",
        [](const Medium& md, std::optional<double> paths, std::optional<double> seconds,
           std::uint64_t seed, int threads, std::optional<double> dr_cm, std::optional<int> nr) {
            volpath::PencilOptions o;
            set_run_control(o, seed, threads, paths, seconds, "paths", 100000);
            const mcml::ProfileGrid g0 = grid_of(md, dr_cm, nr);
            const volpath::PencilGrid g{g0.dr_cm, g0.nr};
            volpath::PencilRun r;
            {
                py::gil_scoped_release release;
                volpath::check_pencil(md, g);
                r = volpath::simulate_pencil(md, g, o);
            }
            r.profile.name = md.name.empty() ? "volpath" : md.name;
            return py::make_tuple(r.profile, r.single);
        },
        py::arg("medium"), py::arg("paths") = py::none(), py::arg("seconds") = py::none(),
        py::arg("seed") = 1, py::arg("threads") = 0, py::arg("dr_cm") = py::none(),
        py::arg("nr") = py::none(),
        "The same pencil beam by the path tracer, the independent engine: (all diffuse "
        "reflectance, its single-scattering part), both Profiles.");
}

// The analytic diffusion profiles: diffusion_models, diffusion_profile.
void bind_diffusion(py::module_& m) {
    // ---- Analytic profiles --------------------------------------------------------------------
    m.def("diffusion_models", &approx::diffusion_model_names,
          "The analytic profile models: dipole, better-dipole, multipole, qd, pbd, burley-*.");
    m.def(
        "diffusion_profile",
        [](const std::string& model, const Medium& md, const Array& r_cm, bool annulus,
           const py::dict& parameters) {
            // A built-in name or a profile file's path (experiments/runner/profile_models.h).
            runner::ProfileModels models;
            const std::string name = models.add(model, "");
            for (const auto& [key, value] : parameters) {
                const auto param = key.cast<std::string>();
                const auto v = py::isinstance<py::sequence>(value)
                                   ? value.cast<std::vector<double>>()
                                   : std::vector<double>{value.cast<double>()};
                if (v.size() != 1 && v.size() != 3)
                    throw std::invalid_argument("parameter \"" + param +
                                                "\": give one value or three (RGB)");
                models.set_parameter(
                    name, param,
                    v.size() == 1 ? std::array{v[0], v[0], v[0]} : std::array{v[0], v[1], v[2]});
            }
            const auto r = r_cm.unchecked<1>();
            Array out({py::ssize_t{3}, r.shape(0)});
            auto o = out.mutable_unchecked<2>();
            std::array<double, 3> total{};
            for (int c = 0; c < 3; ++c) {
                const auto p = models.make(name, approx::diffusion_medium(md, c), c);
                total[static_cast<size_t>(c)] = p->total_rd();
                py::gil_scoped_release release;
                if (!annulus) {
                    for (py::ssize_t i = 0; i < r.shape(0); ++i) o(c, i) = p->rd(r(i));
                } else {
                    // r_cm are bin edges: the area mean over each annulus (what a MC bin holds).
                    for (py::ssize_t i = 0; i + 1 < r.shape(0); ++i)
                        o(c, i) = p->annulus_mean(r(i), r(i + 1));
                    if (r.shape(0) > 0) o(c, r.shape(0) - 1) = NAN;
                }
            }
            return py::make_tuple(out, vec3(total));
        },
        py::arg("model"), py::arg("medium"), py::arg("r_cm"), py::arg("annulus") = false,
        py::arg("parameters") = py::dict(),
        "A built-in model by name, or a profile file by its path (.toml expressions, .bssrdf GLSL "
        "through the headless GL twin; experiments/bssrdf/README.md) with `parameters` {name: "
        "value or [R, G, B]}: "
        "(R_d [1/cm^2] of shape (3, len(r_cm)), R_dr per channel), per unit power entering (no "
        "entry Fresnel factor: multiply by 1 - rsp to compare with the Monte Carlo profiles). "
        "With annulus=True, r_cm are bin edges and each value the area mean over [r_i, r_i+1) "
        "(the last is NaN).");
}

// The separable kernel models and their scores: kernel_models, score_kernel.
void bind_kernels(py::module_& m) {
    // ---- Kernel models ------------------------------------------------------------------------
    m.def("kernel_models", &approx::model_names,
          "The separable kernel models' names (built-in and registered).");
    m.def(
        "score_kernel",
        [](const RadialProfile& p, const std::string& model, int channel, int refine,
           const std::string& material) {
            check_channel(channel);
            if (refine < 1 || refine > 16) throw std::invalid_argument("refine must be in [1, 16]");
            const approx::ModelSpec spec = approx::parse_model(model);
            std::optional<approx::Kernel2D> k;
            approx::ModelResult r;
            approx::KernelErrors e;
            {
                py::gil_scoped_release release;
                k.emplace(p, channel, approx::KernelGrid::from_profile(p, refine));
                r = approx::build_model(spec, *k, {material, channel, {}});
                e = approx::kernel_errors(*k, r.kernel);
            }
            py::dict d;
            d["model"] = r.kernel.model;
            d["rank"] = r.kernel.rank();
            d["h_mm"] = r.kernel.h_mm;
            d["n"] = r.kernel.n;
            d["rms"] = e.rms;
            d["max_abs"] = e.max_abs;
            d["l1_error"] = e.l1_error;
            d["radial_asymmetry"] = e.radial_asymmetry;
            d["build_seconds"] = r.build_seconds;
            d["raw_l1"] = k->raw_l1();
            Array factors({static_cast<size_t>(r.kernel.rank()), static_cast<size_t>(r.kernel.n)});
            Array signs(r.kernel.rank());
            auto f = factors.mutable_unchecked<2>();
            auto s = signs.mutable_unchecked<1>();
            for (py::ssize_t t = 0; t < r.kernel.rank(); ++t) {
                s(t) = r.kernel.terms[static_cast<size_t>(t)].sign;
                for (py::ssize_t i = 0; i < r.kernel.n; ++i)
                    f(t, i) = r.kernel.terms[static_cast<size_t>(t)].a[static_cast<size_t>(i)];
            }
            d["factors"] = factors;
            d["signs"] = signs;
            py::dict info;
            for (const auto& [key, v] : r.info) info[py::str(key)] = v;
            d["info"] = info;
            return d;
        },
        py::arg("profile"), py::arg("model"), py::arg("channel"), py::arg("refine") = 1,
        py::arg("material") = "",
        "Build a separable model (e.g. \"svd:rank=1\", \"preintegration\", \"guided:k=1\") of "
        "one channel's 2D kernel (unit L1, the profile's grid refined `refine` times) and score "
        "it in kernel space: rms, max_abs, l1_error, radial_asymmetry; the model's 1D factors "
        "(rank, n) as cell masses at x = (i + 1/2) h_mm and their signs. `material` names a "
        "Freude14 Table A.1 row for manual:table_a1.");
}

// Scene rendering and the experiment runner: render, run_experiment.
void bind_scenes(py::module_& m) {
    // ---- Scenes and experiments ---------------------------------------------------------------
    m.def(
        "render",
        [](const std::string& scene_path, std::optional<double> spp, std::optional<double> seconds,
           std::uint64_t seed, int threads, int width, int height) {
            const Scene scene = read_scene(scene_path);
            volpath::check_renderable(scene);
            volpath::RenderOptions o;
            set_run_control(o, seed, threads, spp, seconds, "spp", 16);
            if (width < 0 || height < 0 || width > 16384 || height > 16384)
                throw std::invalid_argument("width and height must be in [0, 16384]");
            o.width = width;
            o.height = height;
            volpath::RenderResult r;
            {
                py::gil_scoped_release release;
                r = volpath::render(scene, o);
            }
            py::dict d = image_layers(r.image);
            d["seconds"] = r.seconds;
            d["spp"] = r.spp;
            return d;
        },
        py::arg("scene"), py::arg("spp") = py::none(), py::arg("seconds") = py::none(),
        py::arg("seed") = 1, py::arg("threads") = 0, py::arg("width") = 0, py::arg("height") = 0,
        "Render a scene file with the path tracer: a dict of layers as (height, width, channels) "
        "float32 arrays (radiance, subsurface, specular and their .stderr layers, depth, "
        "normal), seconds and spp.");

    m.def(
        "run_experiment",
        [](const std::string& config, bool quick, const std::string& results, int threads) {
            const runner::Experiment e = runner::read_experiment(config);
            runner::RunOptions o;
            o.quick = quick;
            o.threads = check_threads(threads);
            o.quiet = true;
            o.results_root = results;
            o.command_line = "python: ssslab.run_experiment(\"" + config + "\")";
            py::dict d;
            {
                py::gil_scoped_release release;
                runner::ExperimentRun r = runner::plan(e, o);
                runner::execute(r, o);
                py::gil_scoped_acquire acquire;
                py::dict metrics;
                for (const auto& mt : runner::compute_metrics(r))
                    metrics[py::str(mt.name)] = py::make_tuple(mt.value, mt.se);
                d["metrics"] = metrics;
                d["directory"] = r.out_dir.string();
                d["computed"] = r.computed;
                d["reused"] = r.reused;
            }
            return d;
        },
        py::arg("config"), py::arg("quick") = false, py::arg("results") = "results",
        py::arg("threads") = 0,
        "Run an experiment config as `ssslab run` does (cache under <results>/cache/, outputs "
        "in <results>/<name>/): its directory, what was computed and reused, and its metrics "
        "as {name: (value, standard error)}.");
}

}  // namespace

}  // namespace ssslab::python

PYBIND11_MODULE(ssslab, m) {
    using namespace ssslab::python;
    m.doc() =
        "ssslab: Monte Carlo ground truth for subsurface scattering (an MCML port and a volumetric "
        "path tracer) and the approximations renderers use, scored against it. Units are in the "
        "names: coefficients per cm, R_d per cm^2.";
    m.attr("__version__") = SSSLAB_VERSION;

    bind_errors(m);
    bind_media(m);
    bind_profiles(m);
    bind_engines(m);
    bind_diffusion(m);
    bind_kernels(m);
    bind_scenes(m);
}
