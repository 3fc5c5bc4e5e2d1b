#include "experiments/runner/sphere_study.h"

#include "core/error.h"
#include "core/format.h"
#include "core/material.h"
#include "core/provenance.h"
#include "experiments/runner/profile_models.h"
#include "mcml/profile.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace ssslab::runner {

namespace {

constexpr double kPi = 3.14159265358979323846;
const char* const kCommandLine = "<command line>";

std::array<double, 3> direction(double deg) {
    const double a = deg * kPi / 180.0;
    return {std::sin(a), 0.0, std::cos(a)};
}

// A number from the command line or the config (same key semantics as ConfigTable::number).
double flag_or_config(ConfigTable& t, const std::string& key, const std::optional<double>& flag,
                      const std::string& flag_name, double fallback, const Range& range) {
    const double v = t.number(key, fallback, range);
    if (!flag) return v;
    if (!std::isfinite(*flag) || !range.contains(*flag))
        throw InputError(
            {kCommandLine, 0, 0}, flag_name,
            "expected a number in " + range.describe() + ", got " + format_g(*flag, 9));
    t.record(key, *flag);
    return *flag;
}

Medium read_material(ConfigTable& root, const std::string& material, const std::string& src) {
    if (!material.empty()) {
        if (root.has("material"))
            throw InputError({src, 0, 0}, "--material",
                             "give the material either with --material or in [material], not both");
        auto m = find_material(material);
        if (!m)
            throw InputError({kCommandLine, 0, 0}, "--material",
                             unknown_material_message(material));
        ConfigTable mt = root.table_or_empty("material");
        mt.record("preset", m->name);
        return *m;
    }
    if (!root.has("material"))
        throw InputError({src, 0, 0}, "material",
                         "no material: give --material <name> (one of " + material_names() +
                             ") or a [material] table in --config");
    ConfigTable mt = root.table_or_empty("material");
    Medium m = medium_from_config(mt);
    if (m.name.empty()) m.name = "custom";
    return m;
}

std::vector<std::string> split_list(const std::string& s) {
    std::vector<std::string> out;
    std::stringstream in(s);
    std::string item;
    while (std::getline(in, item, ',')) {
        const auto b = item.find_first_not_of(" \t"), e = item.find_last_not_of(" \t");
        if (b == std::string::npos) continue;
        out.push_back(item.substr(b, e - b + 1));
    }
    return out;
}

// The approx view of the scene (the same camera; checked against volpath's below).
approx::SphereView view_of(const volpath::SphereScene& sc, int supersampling) {
    approx::SphereView v;
    v.to_light = {sc.to_light.x, sc.to_light.y, sc.to_light.z};
    v.to_camera = {sc.to_camera.x, sc.to_camera.y, sc.to_camera.z};
    v.up = {sc.up.x, sc.up.y, sc.up.z};
    v.width = sc.width;
    v.height = sc.height;
    v.frame_scale = sc.frame_scale;
    v.supersampling = supersampling;
    return v;
}

// approx replicates volpath::sphere_camera (approx must not depend on volpath): the frames and
// every pixel centre must agree.
void check_same_camera(const volpath::SphereScene& sc, const approx::SphereView& view) {
    const volpath::SphereCamera cam = volpath::sphere_camera(sc);
    const approx::SphereViewFrame f = approx::resolve_view(view);
    const double R = sc.radius_cm;
    double worst = 0;
    auto cmp = [&](const Vec3& a, const std::array<double, 3>& b) {
        worst = std::max({worst, std::abs(a.x - b[0]), std::abs(a.y - b[1]), std::abs(a.z - b[2])});
    };
    cmp(cam.v, f.v);
    cmp(cam.right, f.right);
    cmp(cam.up, f.up);
    // volpath bins a point into pixel floor((n . right + half_x / R) R / pixel_cm), row
    // floor((half_y / R - n . up) R / pixel_cm): the centre of pixel (x, y) is at
    // ((x + 0.5) pixel_cm - half_x, half_y - (y + 0.5) pixel_cm) / R.
    for (int y = 0; y < sc.height; ++y)
        for (int x = 0; x < sc.width; ++x) {
            const auto p = f.image_point(x, y);
            worst = std::max({worst, std::abs(((x + 0.5) * cam.pixel_cm - cam.half_x) / R - p[0]),
                              std::abs((cam.half_y - (y + 0.5) * cam.pixel_cm) / R - p[1])});
        }
    if (!(worst < 1e-9))
        throw std::logic_error("sphere: the analytic image's camera differs from volpath's by " +
                               format_g(worst, 9) +
                               " R (approx::resolve_view vs volpath::sphere_camera)");
}

// Model against volpath over the beta bins: relative L2 errors (zone-area weighted) over the lit
// (bin centre < 90 deg) and unlit hemispheres, and chi-square over the bins with SE > 0.
SphereComparison compare(const std::vector<double>& model, const std::vector<double>& mc,
                         const std::vector<double>& se, const approx::SphereExitance& t) {
    SphereComparison c;
    double num[2] = {0, 0}, den[2] = {0, 0};
    for (size_t j = 0; j < model.size(); ++j) {
        const int jj = static_cast<int>(j);
        const double b0 = t.beta_edge(jj), b1 = t.beta_edge(jj + 1);
        const double area = std::cos(b0) - std::cos(b1);
        const int h = 0.5 * (b0 + b1) < 0.5 * kPi ? 0 : 1;
        const double d = model[j] - mc[j];
        num[h] += area * d * d;
        den[h] += area * mc[j] * mc[j];
        if (se[j] > 0) {
            c.chi2 += (d / se[j]) * (d / se[j]);
            ++c.dof;
        }
    }
    const double nan = std::numeric_limits<double>::quiet_NaN();
    c.rel_l2_lit = den[0] > 0 ? std::sqrt(num[0] / den[0]) : nan;
    c.rel_l2_unlit = den[1] > 0 ? std::sqrt(num[1] / den[1]) : nan;
    return c;
}

}  // namespace

namespace {

/// A model's error: at its item of the config's `models`, or at --models.
[[noreturn]] void models_error(ConfigTable& root, bool from_config, size_t i,
                               const std::string& msg) {
    if (from_config) root.fail_item("models", i, msg);
    throw InputError({kCommandLine, 0, 0}, "--models", msg);
}

/// The models into `registry`, recorded; `from_config`: they came from the config's `models`.
void read_sphere_models(ConfigTable& root, const SphereStudyInput& a, const std::string& src,
                        ProfileModels& registry, bool& from_config) {
    // Models: `models` in the config (an array of names, or one comma-separated string, which is
    // how the resolved configuration records them) or --models; default dipole, better dipole,
    // photon beam diffusion.
    std::vector<std::string> models = {"dipole", "better-dipole", "pbd"};
    const bool models_in_config = root.has("models");
    if (models_in_config && !a.models.empty())
        throw InputError({src, 0, 0}, "--models",
                         "give the models either with --models or in the config, not both");
    if (models_in_config) {
        try {
            models = *root.optional_string_list("models");
        } catch (const InputError&) {
            models = split_list(root.string("models"));  // not an array: a string, or the error
            if (models.size() == 1 && models[0] == "none") models.clear();
        }
    }
    if (!a.models.empty()) {
        models = split_list(a.models);
        if (models.size() == 1 && models[0] == "none") models.clear();
    }
    from_config = a.models.empty() && models_in_config;
    // Built-in names and profile files (experiments/runner/profile_models.h): a file relative to
    // the config that names it, or to the working directory for --models; the files' parameters
    // from [parameters."<file name>"].
    const std::string base = a.models.empty() && models_in_config
                                 ? std::filesystem::path(src).parent_path().string()
                                 : std::string();
    for (size_t i = 0; i < models.size(); ++i) {
        try {
            registry.add(models[i], base);
        } catch (const std::invalid_argument& e) {
            const std::string msg = e.what();
            models_error(root, from_config, i,
                         msg.starts_with("unknown") ? msg + " (or \"none\")" : msg);
        }
    }
    if (auto pt = root.table("parameters")) registry.read_parameters(*pt);
    {
        // A file from --models is recorded by its absolute path: the resolved configuration
        // resolves paths relative to itself, not to the working directory of this run.
        std::string list;
        for (const auto& n : models) {
            const std::string entry = !a.models.empty() && ProfileModels::is_file_entry(n)
                                          ? std::filesystem::absolute(n).string()
                                          : n;
            list += (list.empty() ? "" : ",") + entry;
        }
        root.record("models", list.empty() ? std::string("none") : list);
    }
}

/// [sphere]: the radius, the light's and the camera's angles, the image and the bins.
void read_sphere_geometry(ConfigTable& root, const SphereStudyInput& a, const std::string& src,
                          SphereJob& job) {
    volpath::SphereScene& sc = job.scene;
    ConfigTable sp = root.table_or_empty("sphere");
    if (a.radius_mm) {
        if (sp.has("radius_mm") || sp.has("radius_cm"))
            throw InputError({src, 0, 0}, "--radius-mm",
                             "give the radius either with --radius-mm or in [sphere], not both");
        if (!std::isfinite(*a.radius_mm) || !(*a.radius_mm > 0))
            throw InputError({kCommandLine, 0, 0}, "--radius-mm",
                             "expected a finite radius > 0 [mm], got " + format_g(*a.radius_mm, 9));
        sc.radius_cm = *a.radius_mm / 10.0;
        sp.record("radius_mm", *a.radius_mm);
    } else if (auto r = optional_length_cm(sp, "radius", Range::positive())) {
        sc.radius_cm = *r;
    } else {
        sc.radius_cm = 0.5;
        sp.record("radius_mm", 5.0);
    }
    job.light_deg =
        flag_or_config(sp, "light_deg", a.light_deg, "--light-deg", 0.0, Range::closed(-180, 180));
    job.camera_deg = flag_or_config(sp, "camera_deg", a.camera_deg, "--camera-deg", 60.0,
                                    Range::closed(-180, 180));
    std::optional<double> size_flag;
    if (a.size) size_flag = *a.size;
    const double size =
        flag_or_config(sp, "size", size_flag, "--size", 256, Range::closed(1, 4096));
    if (size != std::floor(size))
        throw InputError({src, 0, 0}, "size", "expected a whole number of pixels");
    sp.record("size", static_cast<std::int64_t>(size));
    sc.width = sc.height = static_cast<int>(size);
    sc.frame_scale = sp.number("frame_scale", 1.1, Range::positive());
    sc.acceptance_deg = sp.number("acceptance_deg", 10.0, Range::left_open(0, 90));
    sc.beta_bins = static_cast<int>(sp.integer("beta_bins", 180, Range::closed(1, 100000)));
    sc.to_light = {direction(job.light_deg)[0], 0.0, direction(job.light_deg)[2]};
    sc.to_camera = {direction(job.camera_deg)[0], 0.0, direction(job.camera_deg)[2]};
}

/// [budget] and [volpath]: the path tracer's budget, batch and chromatic mode.
void read_sphere_budget(ConfigTable& root, const SphereStudyInput& a, SphereJob& job) {
    ConfigTable budget = root.table_or_empty("budget");
    job.budget = mcml::read_budget(budget);
    job.batch = budget.integer("batch_photons", 0, Range::nonnegative());
    if (a.photons) job.budget.samples = a.photons, budget.record("photons", *a.photons);
    if (a.seconds) job.budget.seconds = a.seconds, budget.record("seconds", *a.seconds);
    if (a.rel_error) job.budget.rel_error = a.rel_error, budget.record("rel_error", *a.rel_error);
    if (a.batch) job.batch = a.batch, budget.record("batch_photons", a.batch);
    if (!job.budget.any()) {
        job.budget.samples = 1'000'000;
        budget.record("photons", static_cast<std::int64_t>(1'000'000));
    }

    ConfigTable vp = root.table_or_empty("volpath");
    job.mode = vp.choice("mode", "analog", {"analog", "hero"});
    if (!a.mode.empty()) {
        if (a.mode != "analog" && a.mode != "hero")
            throw InputError(
                {kCommandLine, 0, 0}, "--mode",
                "expected analog (one run per channel) or hero, got \"" + a.mode + "\"");
        job.mode = a.mode;
        vp.record("mode", a.mode);
    }
}

/// [integration]: the models' quadrature over the sphere and the image's supersampling.
void read_sphere_integration(ConfigTable& root, const SphereStudyInput& a, SphereJob& job) {
    const volpath::SphereScene& sc = job.scene;
    ConfigTable in = root.table_or_empty("integration");
    approx::SphereIntegration& ig = job.integration;
    ig.entry = in.enumerated("entry", approx::EntryWeight::kFresnel);
    if (!a.entry.empty()) {
        const auto e = parse_name<approx::EntryWeight>(a.entry);
        if (!e)
            throw InputError({kCommandLine, 0, 0}, "--entry",
                             "expected " + names_joined<approx::EntryWeight>(" or ") + ", got \"" +
                                 a.entry + "\"");
        ig.entry = *e;
        in.record("entry", a.entry);
    }
    ig.nodes_per_bin = static_cast<int>(in.integer("nodes_per_bin", 4, Range::closed(1, 16)));
    ig.rel_tol = in.number("rel_tol", 1e-10, Range::closed(1e-15, 1e-2));
    job.supersampling = static_cast<int>(in.integer("supersampling", 4, Range::closed(1, 16)));
    ig.radius = sc.radius_cm;
    ig.beta_bins = sc.beta_bins;
    ig.threads = a.threads;
}

/// Everything else the engines would refuse, before any work starts; the models' profiles.
void check_sphere_job(ConfigTable& root, const std::string& src, const ProfileModels& registry,
                      bool from_config, SphereJob& job) {
    const volpath::SphereScene& sc = job.scene;
    const volpath::ChromaticMode mode =
        job.mode == "hero" ? volpath::ChromaticMode::kHero : volpath::ChromaticMode::kPerChannel;
    try {
        volpath::check_sphere(sc, true, mode);
    } catch (const std::invalid_argument& e) {
        throw InputError({src, 0, 0}, "sphere", e.what());
    }
    const Medium& m = sc.medium;
    for (size_t k = 0; k < job.models.size(); ++k) {
        const std::string& name = job.models[k];
        auto& per_channel = job.profiles.emplace_back();
        for (int ch = 0; ch < 3; ++ch) {
            try {
                approx::DiffusionMedium dm = approx::diffusion_medium(m, ch);
                dm.thickness = std::numeric_limits<double>::infinity();  // a sphere, not a slab
                per_channel[static_cast<size_t>(ch)] = registry.make(name, dm, ch);
            } catch (const std::exception& e) {
                models_error(root, from_config, k,
                             "model \"" + name + "\" refuses channel " + kChannelNames[ch] +
                                 " of the material: " + e.what());
            }
        }
    }
}

}  // namespace

SphereJob read_sphere_job(const SphereStudyInput& a) {
    SphereJob job;
    const std::string src = a.config.empty() ? std::string(kCommandLine) : a.config;
    job.source = src;
    job.doc = a.config.empty() ? ConfigDocument::empty(kCommandLine)
                               : ConfigDocument::parse_file(a.config);
    ConfigTable root = job.doc->root();
    volpath::SphereScene& sc = job.scene;
    sc.medium = read_material(root, a.material, src);

    job.seed = static_cast<std::uint64_t>(root.integer("seed", 1, Range::nonnegative()));
    if (a.seed) {
        job.seed = *a.seed;
        root.record("seed", static_cast<std::int64_t>(job.seed));
    }

    bool from_config = false;
    ProfileModels registry;
    read_sphere_models(root, a, src, registry, from_config);
    job.models = registry.names();
    read_sphere_geometry(root, a, src, job);
    read_sphere_budget(root, a, job);
    read_sphere_integration(root, a, job);
    root.finish();
    check_sphere_job(root, src, registry, from_config, job);
    return job;
}

namespace {

/// The analytic models first (seconds: their failures come before the long run).
void integrate_models(const SphereJob& job, SphereStudy& st) {
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<std::array<approx::SphereExitance, 3>>& tables = st.tables;
    tables.resize(job.models.size());
    for (size_t k = 0; k < job.models.size(); ++k)
        for (int ch = 0; ch < 3; ++ch) {
            try {
                tables[k][static_cast<size_t>(ch)] = approx::integrate_sphere(
                    *job.profiles[k][static_cast<size_t>(ch)], job.integration);
            } catch (const std::invalid_argument& e) {
                throw InputError({job.source, 0, 0}, "models",
                                 "model \"" + job.models[k] + "\", channel " + kChannelNames[ch] +
                                     ": " + e.what());
            }
        }
    st.model_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// The image: volpath's layers, then one per model, and what ran in its metadata.
void model_image(const SphereJob& job, const approx::SphereView& view, SphereStudy& st) {
    const volpath::SphereScene& sc = job.scene;
    const std::vector<std::array<approx::SphereExitance, 3>>& tables = st.tables;
    volpath::SphereRun& run = st.run;
    LayeredImage& img = st.image;
    img = std::move(*run.image);
    const int W = sc.width, H = sc.height;
    for (size_t k = 0; k < job.models.size(); ++k) {
        ImageLayer& layer = img.add_layer("model." + job.models[k], 3);
        for (int ch = 0; ch < 3; ++ch) {
            const std::vector<double> pix =
                approx::sphere_exitance_image(tables[k][static_cast<size_t>(ch)], view);
            for (int y = 0; y < H; ++y)
                for (int x = 0; x < W; ++x)
                    layer.at(x, y, ch) =
                        static_cast<float>(pix[static_cast<size_t>(y) * static_cast<size_t>(W) +
                                               static_cast<size_t>(x)]);
        }
    }
    {
        std::string list;
        for (const auto& n : job.models) list += (list.empty() ? "" : ",") + n;
        img.metadata()["ssslab.models"] = list;
        img.metadata()["ssslab.material"] = sc.medium.name;
        img.metadata()["ssslab.radius_cm"] = format_g(sc.radius_cm, 9);
        img.metadata()["ssslab.entry"] = approx::to_string(job.integration.entry);
    }
}

/// The preview: volpath's exitance and the models side by side, one exposure.
void model_preview(const SphereJob& job, SphereStudy& st) {
    const int W = job.scene.width, H = job.scene.height;
    const LayeredImage& img = st.image;
    const int panels = 1 + static_cast<int>(job.models.size());
    st.preview = LayeredImage(W * panels, H);
    LayeredImage& preview = st.preview;
    ImageLayer& pv = preview.add_layer("preview", 3);
    std::vector<float> values;
    for (int p = 0; p < panels; ++p) {
        const ImageLayer& src = img.layer(
            p == 0 ? std::string("exitance") : "model." + job.models[static_cast<size_t>(p - 1)]);
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x)
                for (int ch = 0; ch < 3; ++ch) {
                    pv.at(p * W + x, y, ch) = src.at(x, y, ch);
                    if (p == 0 && src.at(x, y, ch) > 0) values.push_back(src.at(x, y, ch));
                }
    }
    double& exposure = st.exposure;
    if (!values.empty()) {
        const size_t q = static_cast<size_t>(0.995 * static_cast<double>(values.size() - 1));
        std::nth_element(values.begin(), values.begin() + static_cast<long>(q), values.end());
        if (values[q] > 0) exposure = -std::log2(static_cast<double>(values[q]));
    }
}

/// The beta profile table and the models' comparisons with the path tracer.
void compare_models(const SphereJob& job, SphereStudy& st) {
    const volpath::SphereScene& sc = job.scene;
    const std::vector<std::array<approx::SphereExitance, 3>>& tables = st.tables;
    const volpath::SphereRun& run = st.run;
    std::vector<std::array<SphereComparison, 3>>& cmp = st.cmp;
    cmp.resize(job.models.size());
    std::array<std::vector<double>, 3> bins_mc, bins_se;
    for (int ch = 0; ch < 3; ++ch) {
        bins_mc[static_cast<size_t>(ch)] = run.exitance[static_cast<size_t>(ch)];
        bins_se[static_cast<size_t>(ch)] = run.exitance_se[static_cast<size_t>(ch)];
    }
    // Like with like: a model without single scattering is compared with volpath's multiple-
    // scattering part M - M_ss (its SE taken as the total's: the two parts come from disjoint
    // paths, Var(ms) = Var(all) - Var(ss) + O(mean(ms) mean(ss) / N)).
    std::array<std::vector<double>, 3> bins_ms;
    for (int ch = 0; ch < 3; ++ch) {
        const size_t c3 = static_cast<size_t>(ch);
        bins_ms[c3] = bins_mc[c3];
        for (size_t j = 0; j < bins_ms[c3].size(); ++j)
            bins_ms[c3][j] -= run.exitance_single[c3][j];
    }
    auto reference = [&](size_t k, size_t c3) -> const std::vector<double>& {
        return job.profiles[k][c3]->includes_single_scattering() ? bins_mc[c3] : bins_ms[c3];
    };
    for (size_t k = 0; k < job.models.size(); ++k)
        for (int ch = 0; ch < 3; ++ch) {
            const size_t c3 = static_cast<size_t>(ch);
            cmp[k][c3] =
                compare(tables[k][c3].bin_mean, reference(k, c3), bins_se[c3], tables[k][c3]);
        }
    std::string& csv = st.beta_csv;
    csv = "beta_lo_deg,beta_hi_deg";
    for (int ch = 0; ch < 3; ++ch) {
        const std::string cn = kChannelNames[ch];
        csv += ",M_volpath_" + cn + ",M_volpath_se_" + cn + ",M_volpath_single_" + cn +
               ",M_volpath_single_se_" + cn;
        // z against the total for models with single scattering, else against M - M_ss.
        for (const auto& n : job.models) csv += ",M_" + n + "_" + cn + ",z_" + n + "_" + cn;
    }
    csv += "\n";
    for (int j = 0; j < sc.beta_bins; ++j) {
        const size_t jj = static_cast<size_t>(j);
        csv += format_g(run.beta_edge(j) * 180.0 / kPi, 9) + "," +
               format_g(run.beta_edge(j + 1) * 180.0 / kPi, 9);
        for (int ch = 0; ch < 3; ++ch) {
            const size_t c3 = static_cast<size_t>(ch);
            const double v = bins_mc[c3][jj], se = bins_se[c3][jj];
            csv += "," + format_g(v, 9) + "," + format_g(se, 9) + "," +
                   format_g(run.exitance_single[c3][jj], 9) + "," +
                   format_g(run.exitance_single_se[c3][jj], 9);
            for (size_t k = 0; k < job.models.size(); ++k) {
                const double m = tables[k][c3].bin_mean[jj];
                const double ref = reference(k, c3)[jj];
                csv += "," + format_g(m, 9) + "," +
                       (se > 0 ? format_g((m - ref) / se, 9) : std::string("nan"));
            }
        }
        csv += "\n";
    }
}

/// The resolved configuration: results per channel, timing, provenance.
void record_results(SphereJob& job, SphereStudy& st, const std::string& command_line) {
    const std::vector<std::array<approx::SphereExitance, 3>>& tables = st.tables;
    const std::vector<std::array<SphereComparison, 3>>& cmp = st.cmp;
    const volpath::SphereRun& run = st.run;
    const double model_seconds = st.model_seconds;
    ConfigTable root = job.doc->root();
    for (int ch = 0; ch < 3; ++ch) {
        const size_t c3 = static_cast<size_t>(ch);
        const BatchRunResult& r = run.runs[run.mode == volpath::ChromaticMode::kHero ? 0 : c3];
        ConfigTable t = root.table_or_empty(std::string("result_") + kChannelNames[ch]);
        t.record("engine", std::string(volpath::sphere_engine_version()));
        t.record("stop_reason", std::string(to_string(r.reason)));
        t.record("photons", static_cast<std::int64_t>(r.samples));
        t.record("batches", static_cast<std::int64_t>(r.batches));
        t.record("threads", static_cast<std::int64_t>(r.threads));
        t.record("wall_seconds", r.seconds);
        t.record("diffuse_fraction", run.diffuse[c3]);
        t.record("diffuse_fraction_se", run.diffuse_se[c3]);
        t.record("diffuse_single_fraction", run.diffuse_single[c3]);
        t.record("diffuse_single_fraction_se", run.diffuse_single_se[c3]);
        t.record("specular_fraction", run.specular[c3]);
        t.record("specular_fraction_se", run.specular_se[c3]);
        t.record("specular_fraction_expected", run.specular_expected);
        t.record("long_path_roulette_mass", run.lost[c3]);
        for (size_t k = 0; k < job.models.size(); ++k) {
            const std::string n = job.models[k];
            const approx::SphereExitance& tb = tables[k][c3];
            t.record(n + "_total_rd", job.profiles[k][c3]->total_rd());
            t.record(n + "_diffuse_fraction", tb.total_fraction());
            t.record(n + "_compared_with",
                     std::string(job.profiles[k][c3]->includes_single_scattering()
                                     ? "volpath_total"
                                     : "volpath_multiple_scattering"));
            t.record(n + "_rel_l2_lit", cmp[k][c3].rel_l2_lit);
            t.record(n + "_rel_l2_unlit", cmp[k][c3].rel_l2_unlit);
            t.record(n + "_chi2", cmp[k][c3].chi2);
            t.record(n + "_chi2_dof", static_cast<std::int64_t>(cmp[k][c3].dof));
            t.record(n + "_quadrature_rel_error", tb.max_rel_error);
            t.record(n + "_profile_evaluations", static_cast<std::int64_t>(tb.evaluations));
        }
    }
    {
        ConfigTable t = root.table_or_empty("timing");
        t.record("volpath_seconds", run.seconds);
        t.record("volpath_paths", static_cast<std::int64_t>(run.paths));
        t.record("volpath_scattering_events", static_cast<std::int64_t>(run.events));
        t.record("models_seconds", model_seconds);
    }
    job.doc->add_resolved_section("provenance", provenance(command_line));
    st.resolved_toml =
        "# ssslab sphere: resolved configuration, results per channel, timing, provenance\n" +
        job.doc->resolved_toml();
}

}  // namespace

SphereStudy run_sphere_study(SphereJob& job, volpath::SphereOptions so,
                             const std::string& command_line) {
    SphereStudy st;
    volpath::SphereScene& sc = job.scene;
    const approx::SphereView view = view_of(sc, job.supersampling);
    check_same_camera(sc, view);
    integrate_models(job, st);

    // The path tracer.
    so.seed = job.seed;
    so.threads = job.integration.threads;
    so.budget = job.budget;
    so.batch_paths = job.batch;
    so.mode =
        job.mode == "hero" ? volpath::ChromaticMode::kHero : volpath::ChromaticMode::kPerChannel;
    so.image = true;
    st.run = volpath::simulate_sphere(sc, so);
    if (st.run.interrupted) return st;

    model_image(job, view, st);
    model_preview(job, st);
    compare_models(job, st);
    record_results(job, st, command_line);
    return st;
}

}  // namespace ssslab::runner
