#include "experiments/runner/kernel_study.h"

#include "approx/convolve.h"
#include "approx/kernel2d.h"
#include "approx/models.h"
#include "core/error.h"
#include "core/format.h"
#include "core/image_io.h"
#include "core/material.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <set>
#include <sstream>

namespace ssslab::runner {

namespace {

using Clock = std::chrono::steady_clock;

// [Freude14 Table 6.3]: kernel-space RMS, normalised so that the table's largest entry
// (Ketchup, manual, B) is 1.
struct ThesisRow {
    const char* material;
    const char* model;
    double rgb[3];
};
const std::vector<ThesisRow>& thesis_table_6_3() {
    static const std::vector<ThesisRow> t = {
        {"Apple", "svd1", {0.057, 0.058, 0.066}},
        {"Marble", "svd1", {0.038, 0.041, 0.045}},
        {"Ketchup", "svd1", {0.061, 0.161, 0.157}},
        {"Skin1", "svd1", {0.035, 0.062, 0.095}},
        {"Wholemilk", "svd1", {0.036, 0.040, 0.046}},
        {"Apple", "pre", {0.120, 0.122, 0.142}},
        {"Marble", "pre", {0.079, 0.088, 0.096}},
        {"Ketchup", "pre", {0.139, 0.370, 0.354}},
        {"Skin1", "pre", {0.074, 0.142, 0.226}},
        {"Wholemilk", "pre", {0.074, 0.084, 0.099}},
        {"Apple", "guided1", {0.137, 0.141, 0.162}},
        {"Marble", "guided1", {0.090, 0.099, 0.110}},
        {"Ketchup", "guided1", {0.141, 0.167, 0.160}},
        {"Skin1", "guided1", {0.084, 0.166, 0.230}},
        {"Wholemilk", "guided1", {0.084, 0.097, 0.115}},
        {"Apple", "manual", {0.106, 0.107, 0.118}},
        {"Marble", "manual", {0.077, 0.074, 0.075}},
        {"Ketchup", "manual", {0.151, 0.683, 1.000}},
        {"Skin1", "manual", {0.093, 0.202, 0.261}},
        {"Wholemilk", "manual", {0.070, 0.081, 0.091}},
    };
    return t;
}

// Which thesis column a model spec corresponds to ("" if none).
std::string thesis_column(const approx::ModelSpec& m) {
    if (m.name == "svd" && m.number("rank", 1) == 1 && !m.flag("l1")) return "svd1";
    if (m.name == "preintegration") return "pre";
    if (m.name == "guided" && m.number("k", 1) == 1 && m.number("b", 0) == 0) return "guided1";
    if (m.name == "manual" && m.flag("table_a1")) return "manual";
    return "";
}

// Radius holding `fraction` of the mass of an even 1D kernel (half cell masses).
double mass_radius(const std::vector<double>& half, double h, double fraction) {
    double total = 0;
    for (double v : half) total += v;
    double run = 0;
    for (size_t i = 0; i < half.size(); ++i) {
        run += half[i];
        if (run >= fraction * total) return static_cast<double>(i + 1) * h;
    }
    return static_cast<double>(half.size()) * h;
}

std::string png_of(const approx::ImageRGB& img) {
    return encode_png_rgb8(img.width, img.height, approx::to_rgb8(img, true));
}

}  // namespace

const char* kernel_study_version() {
    return "kernel-study-4";
}

std::string KernelStudySpec::canonical() const {
    std::ostringstream os;
    os << "name=" << name << "\nmaterials=";
    for (const auto& m : materials) os << m << ",";
    os << "\nmodels=";
    for (const auto& m : models) os << m.cache_text() << ";";
    os << "\nsignals=";
    for (auto s : signals) os << approx::signal_name(s) << ",";
    os << "\ntaps=" << taps << "\njitter=" << format_g(jitter, 8) << "\npixels=" << pixels
       << "\nfov_mm=" << format_g(fov_mm, 8) << "\nrefine=" << refine << "\nimages=" << images
       << "\nkernel_plots=" << kernel_plots << "\nsingular_values=" << singular_values
       << "\ncompare=" << compare << "\nreference=" << reference << "\n";
    return os.str();
}

KernelStudySpec read_kernel_study(ConfigTable& t, const std::vector<std::string>& labels) {
    KernelStudySpec s;
    s.name = t.string("name");
    if (s.name.empty() ||
        s.name.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789_-") != std::string::npos)
        t.fail("name", "expected a name of lower-case letters, digits, '_' and '-', got \"" +
                           s.name + "\"");
    if (auto ms = t.optional_string_list("materials")) {
        s.materials = *ms;
        for (size_t i = 0; i < s.materials.size(); ++i)
            if (std::find(labels.begin(), labels.end(), s.materials[i]) == labels.end())
                t.fail_item("materials", i,
                            "\"" + s.materials[i] + "\" is not a material of this experiment");
    } else {
        s.materials = labels;
    }
    if (s.materials.empty()) t.fail("materials", "expected at least one material");
    const std::vector<std::string> models =
        t.optional_string_list("models").value_or(std::vector<std::string>{});
    std::set<std::string> seen;
    for (size_t i = 0; i < models.size(); ++i) {
        try {
            s.models.push_back(approx::parse_model(models[i]));
        } catch (const std::invalid_argument& e) {
            t.fail_item("models", i, e.what());
        }
        if (!seen.insert(s.models.back().label()).second)
            t.fail_item("models", i, "model \"" + models[i] + "\" is listed twice");
    }
    if (auto names = t.optional_string_list("signals"))
        for (size_t i = 0; i < names->size(); ++i) {
            const std::string& name = (*names)[i];
            approx::Signal sig;
            if (!approx::parse_signal(name, sig))
                t.fail_item("signals", i,
                            "unknown signal \"" + name +
                                "\"; signals: edge, circle_squares, dot, skin_shaded, "
                                "skin_uniform");
            s.signals.push_back(sig);
        }
    s.taps = static_cast<int>(t.integer("taps", 17, Range::closed(0, 1001)));
    if (s.taps != 0 && (s.taps < 3 || s.taps % 2 == 0))
        t.fail("taps",
               "expected 0 (none) or an odd number of taps >= 3, got " + std::to_string(s.taps));
    s.jitter = t.number("jitter", 0.0, Range::closed(0, 1));
    s.pixels = static_cast<int>(t.integer("pixels", 256, Range::closed(16, 4096)));
    s.fov_mm = t.optional_number("fov_mm", Range::positive()).value_or(0.0);
    s.refine = static_cast<int>(t.integer("refine", 1, Range::closed(1, 8)));
    s.images = t.boolean("images", false);
    s.kernel_plots = t.boolean("kernel_plots", false);
    s.singular_values = static_cast<int>(t.integer("singular_values", 0, Range::closed(0, 200)));
    s.compare = t.choice("compare", "", {"", "freude14_table_6_3"});
    if (auto ref = t.optional_string("reference")) {
        s.reference = *ref;
        if (std::none_of(s.models.begin(), s.models.end(),
                         [&](const approx::ModelSpec& m) { return m.text == s.reference; }))
            t.fail("reference", "\"" + s.reference + "\" is not one of this study's models");
        if (s.signals.empty()) t.fail("reference", "a reference needs signals");
    }
    if (s.models.empty() && s.singular_values == 0)
        t.fail("models", "expected at least one model (or singular_values > 0)");
    if (s.models.empty() &&
        (!s.signals.empty() || s.images || s.kernel_plots || !s.compare.empty()))
        t.fail("models", "signals, images, kernel_plots and compare need models");
    return s;
}

namespace {

// One model's kernel-space RMS in one channel, for the Table 6.3 comparison.
struct Rms {
    std::string material, column, spec;
    int channel;
    double rms;
};

// Per model, over materials and channels: what Table 5.1 lists, measured.
struct Aggregate {
    int rank = 0, convolutions = 0, kernels = 0;
    double build_sum = 0, build_max = 0, kernel_rms_sum = 0, l1_error_max = 0;
    double image_rms_sum = 0, taps_rms_sum = 0;
    int images = 0, taps_images = 0;
};

using SignalImages = std::pair<approx::ImageRGB, approx::ImageRGB>;

// The image grid: given, or 8 times the radius holding 90 % of the widest channel's
// pre-integrated kernel.
double image_fov(const KernelStudySpec& spec,
                 const std::vector<std::unique_ptr<approx::Kernel2D>>& k,
                 const approx::KernelGrid& grid) {
    double fov = spec.fov_mm;
    if (fov <= 0) {
        double r90 = 0;
        for (int c = 0; c < 3; ++c) {
            const approx::ModelResult p = approx::preintegration(*k[static_cast<size_t>(c)]);
            r90 = std::max(r90, mass_radius(p.kernel.terms[0].a, grid.h_mm, 0.9));
        }
        fov = 8.0 * r90;
    }
    return fov;
}

// One material of a study: its three 2D kernels, the image grid, the test signals made so far
// and the models built from its kernels.
struct MaterialKernels {
    std::string material;
    approx::KernelGrid grid;
    std::vector<std::unique_ptr<approx::Kernel2D>> k;
    double fov = 0;
    approx::SignalParams sp;
    // Each signal and its exact convolution, made once (image-space fits use them too).
    std::map<approx::Signal, SignalImages> signal_images;
    // Models, per channel.
    std::vector<std::array<approx::ModelResult, 3>> built;

    MaterialKernels(const KernelStudySpec& spec, const std::string& material_,
                    const RadialProfile& profile)
        : material(material_), grid(approx::KernelGrid::from_profile(profile, spec.refine)) {
        for (int c = 0; c < 3; ++c)
            k.push_back(std::make_unique<approx::Kernel2D>(profile, c, grid));
    }

    // The image grid's signal parameters, once the kernels are known.
    void set_image_grid(const KernelStudySpec& spec) {
        fov = image_fov(spec, k, grid);
        sp.size = spec.pixels;
        sp.pixel_mm = fov / spec.pixels;
        sp.dot_radius_mm = fov / 64.0;
    }

    // A signal and its exact convolution with the three kernels, made at the first call.
    const SignalImages& images_of(approx::Signal sig) {
        auto it = signal_images.find(sig);
        if (it == signal_images.end()) {
            approx::ImageRGB e = approx::make_signal(sig, sp);
            approx::ImageRGB exact =
                approx::convolve_exact(e, {k[0].get(), k[1].get(), k[2].get()});
            it = signal_images.emplace(sig, std::make_pair(std::move(e), std::move(exact))).first;
        }
        return it->second;
    }
};

// One kernel study's run: its tables, metrics and files, filled material by material.
class KernelStudyRun {
  public:
    explicit KernelStudyRun(const KernelStudySpec& spec) : spec_(spec), agg_(spec.models.size()) {
        kernels_ << "material,channel,model,label,rank,convolutions_1d,build_s,kernel_rms,"
                    "max_abs,sum,l1_error,radial_asymmetry,constraint_error,iterations,grid_n,"
                    "h_mm\n";
        image_ << "material,signal,model,label,sampling,channel,rms,max_abs,energy,fov_mm,pixels\n";
        singular_ << "material,channel,index,sigma,sigma_over_sigma1\n";
        slices_ << "material,channel,model,direction,r_mm,value_per_mm2\n";
        versus_ << "material,signal,model,reference,channel,rms\n";
        metrics_ << "metric,unit,value,tolerance\n";
    }

    // Every table and study of one material.
    void add_material(const std::string& material, const RadialProfile& profile) {
        MaterialKernels mk(spec_, material, profile);
        if (spec_.singular_values > 0) write_singular_values(mk);
        mk.set_image_grid(spec_);
        build_models(mk);
        if (spec_.kernel_plots) write_slices(mk);
        for (approx::Signal sig : spec_.signals) score_signal(mk, sig);
    }

    // The files of the study (after every material).
    std::map<std::string, std::string> files() {
        files_["kernels.csv"] = kernels_.str();
        if (!spec_.signals.empty()) files_["image.csv"] = image_.str();
        if (spec_.singular_values > 0) files_["singular_values.csv"] = singular_.str();
        if (spec_.kernel_plots) files_["slices.csv"] = slices_.str();
        if (!spec_.reference.empty()) files_["image_vs_reference.csv"] = versus_.str();
        if (spec_.compare == "freude14_table_6_3") files_["comparison.csv"] = comparison_csv();
        if (!spec_.models.empty()) files_["properties.csv"] = properties_csv();
        files_["metrics.csv"] = metrics_.str();
        return std::move(files_);
    }

  private:
    const KernelStudySpec& spec_;
    std::map<std::string, std::string> files_;
    std::ostringstream kernels_, image_, singular_, slices_, versus_;
    std::vector<Rms> for_compare_;
    std::vector<Aggregate> agg_;
    // Regression metrics (`ssslab check`): deterministic functions of the fixed-seed profiles.
    std::ostringstream metrics_;

    // One regression metric.
    void metric(const std::string& name, const char* unit, double v) {
        metrics_ << name << ',' << unit << ',' << format_g(v, 17) << ",1e-4\n";
    }

    // The aggregate of model m (a reference into spec_.models).
    Aggregate& aggregate_of(const approx::ModelSpec& m) {
        return agg_[static_cast<size_t>(&m - spec_.models.data())];
    }

    // The leading singular values of each channel's kernel (Freude14 Fig. 5.1).
    void write_singular_values(const MaterialKernels& mk) {
        for (int c = 0; c < 3; ++c) {
            const auto sv =
                approx::singular_values(*mk.k[static_cast<size_t>(c)], spec_.singular_values);
            for (size_t i = 0; i < sv.size(); ++i) {
                singular_ << mk.material << ',' << kChannelNames[c] << ',' << i + 1 << ','
                          << format_g(sv[i], 8) << ',' << format_g(sv[i] / sv[0], 8) << '\n';
                if (i > 0 && i < 6)
                    metric(spec_.name + "." + mk.material + "." + kChannelNames[c] + ".sigma" +
                               std::to_string(i + 1) + "_over_sigma1",
                           "1", sv[i] / sv[0]);
            }
        }
    }

    // Every model for every channel, scored in kernel space.
    void build_models(MaterialKernels& mk) {
        auto fit = [&mk](approx::Signal sig) -> const SignalImages& { return mk.images_of(sig); };
        for (const auto& m : spec_.models) {
            std::array<approx::ModelResult, 3> r;
            for (int c = 0; c < 3; ++c) {
                r[static_cast<size_t>(c)] =
                    approx::build_model(m, *mk.k[static_cast<size_t>(c)], {mk.material, c, fit});
                record_kernel(mk, m, c, r[static_cast<size_t>(c)]);
            }
            mk.built.push_back(std::move(r));
        }
    }

    // One built model's kernel-space errors: its row, its share of the aggregate, its metric.
    void record_kernel(const MaterialKernels& mk, const approx::ModelSpec& m, int c,
                       const approx::ModelResult& x) {
        const approx::KernelErrors e =
            approx::kernel_errors(*mk.k[static_cast<size_t>(c)], x.kernel);
        auto info = [&](const char* key) {
            const auto it = x.info.find(key);
            return it == x.info.end() ? std::string() : format_g(it->second, 8);
        };
        kernels_ << mk.material << ',' << kChannelNames[c] << ",\"" << m.text << "\"," << m.label()
                 << ',' << x.kernel.rank() << ',' << x.kernel.convolutions_1d() << ','
                 << format_g(x.build_seconds, 8) << ',' << format_g(e.rms, 8) << ','
                 << format_g(e.max_abs, 8) << ',' << format_g(x.kernel.sum(), 8) << ','
                 << format_g(e.l1_error, 8) << ',' << format_g(e.radial_asymmetry, 8) << ','
                 << info("constraint_error") << ',' << info("iterations") << ',' << mk.grid.n << ','
                 << format_g(mk.grid.h_mm, 8) << '\n';
        const std::string col = thesis_column(m);
        if (!col.empty()) for_compare_.push_back({mk.material, col, m.text, c, e.rms});
        Aggregate& g = aggregate_of(m);
        g.rank = std::max(g.rank, x.kernel.rank());
        g.convolutions = std::max(g.convolutions, x.kernel.convolutions_1d());
        ++g.kernels;
        g.build_sum += x.build_seconds;
        g.build_max = std::max(g.build_max, x.build_seconds);
        g.kernel_rms_sum += e.rms;
        g.l1_error_max = std::max(g.l1_error_max, std::fabs(e.l1_error));
        metric(spec_.name + "." + mk.material + "." + m.label() + "." + kChannelNames[c] +
                   ".kernel_rms",
               "1", e.rms);
    }

    // Slices as Freude14 Fig. 6.2: along the main axis (cells (i, 0)) and the diagonal
    // (cells (i, i)), at most 400 points each.
    void write_slices(const MaterialKernels& mk) {
        for (int c = 0; c < 3; ++c) {
            const approx::Kernel2D& kc = *mk.k[static_cast<size_t>(c)];
            const int n = kc.n(), stride = std::max(1, n / 400);
            const double h = kc.h_mm(), area = h * h;
            auto emit = [&](const std::string& model, auto value) {
                for (int i = 0; i < n; i += stride) {
                    slices_ << mk.material << ',' << kChannelNames[c] << ',' << model << ",axis,"
                            << format_g(std::sqrt((i + 0.5) * (i + 0.5) + 0.25) * h, 8) << ','
                            << format_g(value(i, 0) / area, 8) << '\n';
                    slices_ << mk.material << ',' << kChannelNames[c] << ',' << model
                            << ",diagonal," << format_g((i + 0.5) * std::sqrt(2.0) * h, 8) << ','
                            << format_g(value(i, i) / area, 8) << '\n';
                }
            };
            emit("ground_truth", [&](int i, int j) { return kc.at(i, j); });
            for (size_t mi = 0; mi < mk.built.size(); ++mi) {
                const approx::SeparableKernel& sk = mk.built[mi][static_cast<size_t>(c)].kernel;
                emit(spec_.models[mi].label(), [&](int i, int j) { return sk.at(i, j); });
            }
        }
    }

    // Every model applied to one test signal (full resolution, taps, jittered taps), scored
    // against the exact convolution and, with a reference, against the reference model's image.
    void score_signal(MaterialKernels& mk, approx::Signal sig) {
        // Not a structured binding: lambdas below capture them (Clang 14 cannot).
        const auto& images = mk.images_of(sig);
        const auto& e = std::get<0>(images);
        const auto& exact = std::get<1>(images);
        std::vector<std::pair<std::string, approx::ImageRGB>> outs;
        auto record = [&](const approx::ModelSpec& m, const std::string& sampling,
                          const approx::ImageRGB& out) {
            record_image(mk, sig, m, sampling, out, exact);
        };
        for (size_t mi = 0; mi < mk.built.size(); ++mi) {
            const auto& m = spec_.models[mi];
            const std::array<const approx::SeparableKernel*, 3> a = {
                &mk.built[mi][0].kernel, &mk.built[mi][1].kernel, &mk.built[mi][2].kernel};
            const approx::ImageRGB full = approx::convolve_separable(e, a);
            record(m, "full", full);
            outs.push_back({m.label(), full});
            if (spec_.taps > 0 && mk.built[mi][0].kernel.rank() == 1) {
                const approx::TapKernel taps = approx::make_taps(a, spec_.taps);
                record(m, "taps" + std::to_string(spec_.taps), approx::convolve_taps(e, taps, 0.0));
                if (spec_.jitter > 0)
                    record(m, "taps" + std::to_string(spec_.taps) + "_jitter",
                           approx::convolve_taps(e, taps, spec_.jitter));
            }
        }
        if (!spec_.reference.empty()) write_versus_reference(mk, sig, outs);
        if (spec_.images) write_images(mk, sig, e, exact, outs);
    }

    // One model's image of a signal against the exact one: its rows, aggregate and metric.
    void record_image(const MaterialKernels& mk, approx::Signal sig, const approx::ModelSpec& m,
                      const std::string& sampling, const approx::ImageRGB& out,
                      const approx::ImageRGB& exact) {
        const approx::ImageErrors ie = approx::image_errors(out, exact);
        const double mean_rms = (ie.rms[0] + ie.rms[1] + ie.rms[2]) / 3.0;
        Aggregate& g = aggregate_of(m);
        if (sampling == "full") {
            g.image_rms_sum += mean_rms;
            ++g.images;
        } else if (sampling.find("jitter") == std::string::npos) {
            g.taps_rms_sum += mean_rms;
            ++g.taps_images;
        }
        metric(spec_.name + "." + mk.material + "." + approx::signal_name(sig) + "." + m.label() +
                   "." + sampling + ".image_rms",
               "1", mean_rms);
        for (int c = 0; c < 3; ++c)
            image_ << mk.material << ',' << approx::signal_name(sig) << ",\"" << m.text << "\","
                   << m.label() << ',' << sampling << ',' << kChannelNames[c] << ','
                   << format_g(ie.rms[static_cast<size_t>(c)], 8) << ','
                   << format_g(ie.max_abs[static_cast<size_t>(c)], 8) << ','
                   << format_g(ie.energy[static_cast<size_t>(c)], 8) << ',' << format_g(mk.fov, 8)
                   << ',' << spec_.pixels << '\n';
    }

    // Every model's full-resolution image of a signal against the reference model's.
    void write_versus_reference(const MaterialKernels& mk, approx::Signal sig,
                                const std::vector<std::pair<std::string, approx::ImageRGB>>& outs) {
        const approx::ImageRGB* ref = nullptr;
        for (size_t mi = 0; mi < mk.built.size(); ++mi)
            if (spec_.models[mi].text == spec_.reference) ref = &outs[mi].second;
        for (size_t mi = 0; mi < mk.built.size(); ++mi) {
            if (&outs[mi].second == ref) continue;
            const approx::ImageErrors ie = approx::image_errors(outs[mi].second, *ref);
            for (int c = 0; c < 3; ++c)
                versus_ << mk.material << ',' << approx::signal_name(sig) << ",\""
                        << spec_.models[mi].text << "\",\"" << spec_.reference << "\","
                        << kChannelNames[c] << ',' << format_g(ie.rms[static_cast<size_t>(c)], 8)
                        << '\n';
        }
    }

    // The signal, its exact convolution, every model's image and its difference as PNGs.
    void write_images(const MaterialKernels& mk, approx::Signal sig, const approx::ImageRGB& e,
                      const approx::ImageRGB& exact,
                      const std::vector<std::pair<std::string, approx::ImageRGB>>& outs) {
        const std::string dir = "images/" + mk.material + "/" + approx::signal_name(sig) + "/";
        files_[dir + "input.png"] = png_of(e);
        files_[dir + "exact.png"] = png_of(exact);
        // Differences normalised across the models of this signal, as the thesis.
        double scale = 1e-30;
        for (const auto& [label, out] : outs) {
            const approx::ImageErrors ie = approx::image_errors(out, exact);
            for (double v : ie.max_abs) scale = std::max(scale, v);
        }
        for (const auto& [label, out] : outs) {
            files_[dir + label + ".png"] = png_of(out);
            files_[dir + label + "_diff.png"] =
                encode_png_rgb8(out.width, out.height, approx::difference_rgb8(out, exact, scale));
        }
    }

    // The kernel-space RMS beside [Freude14 Table 6.3].
    std::string comparison_csv() const {
        // Normalise as the thesis did: by the entry its table is normalised to (Ketchup, manual,
        // B) when the study has it, otherwise by the study's largest entry.
        double ref = 0;
        for (const auto& x : for_compare_) ref = std::max(ref, x.rms);
        for (const auto& x : for_compare_)
            if (x.material == "Ketchup" && x.column == "manual" && x.channel == 2) ref = x.rms;
        auto thesis_of = [](const std::string& material, const std::string& column, int c) {
            for (const auto& row : thesis_table_6_3())
                if (material == row.material && column == row.model) return row.rgb[c];
            return -1.0;
        };
        // Within a material and channel the ratio to SVD rank-1 does not depend on how the table
        // is normalised, nor on the grid's cell count: the like-for-like comparison.
        std::map<std::pair<std::string, int>, double> svd1;
        for (const auto& x : for_compare_)
            if (x.column == "svd1") svd1[{x.material, x.channel}] = x.rms;
        std::ostringstream cmp;
        cmp << "material,model,thesis_column,channel,rms,normalised,thesis_normalised,ratio,"
               "over_svd1,thesis_over_svd1,ratio_over_svd1\n";
        for (const auto& x : for_compare_) {
            const double thesis = thesis_of(x.material, x.column, x.channel);
            const double norm = ref > 0 ? x.rms / ref : 0;
            const auto s1 = svd1.find({x.material, x.channel});
            const double t1 = thesis_of(x.material, "svd1", x.channel);
            const double ours = s1 != svd1.end() && s1->second > 0 ? x.rms / s1->second : -1;
            const double theirs = thesis > 0 && t1 > 0 ? thesis / t1 : -1;
            cmp << x.material << ",\"" << x.spec << "\"," << x.column << ','
                << kChannelNames[x.channel] << ',' << format_g(x.rms, 8) << ',' << format_g(norm, 8)
                << ',' << (thesis >= 0 ? format_g(thesis, 8) : "") << ','
                << (thesis > 0 ? format_g(norm / thesis, 8) : "") << ','
                << (ours >= 0 ? format_g(ours, 8) : "") << ','
                << (theirs >= 0 ? format_g(theirs, 8) : "") << ','
                << (ours >= 0 && theirs > 0 ? format_g(ours / theirs, 8) : "") << '\n';
        }
        return cmp.str();
    }

    // [Freude14 Table 5.1], filled from this study's measurements.
    std::string properties_csv() const {
        std::ostringstream pr;
        pr << "model,label,rank,separable,convolutions_1d,closed_form,build_s_mean,build_s_max,"
              "kernel_rms_mean,l1_error_max,image_rms_mean,taps_rms_mean\n";
        for (size_t i = 0; i < spec_.models.size(); ++i) {
            const Aggregate& g = agg_[i];
            const approx::ModelSpec& m = spec_.models[i];
            pr << '"' << m.text << "\"," << m.label() << ',' << g.rank << ','
               << (g.rank == 1 ? "yes" : "no") << ',' << g.convolutions << ','
               << (m.closed_form() ? "yes" : "no") << ','
               << format_g(g.kernels ? g.build_sum / g.kernels : 0, 8) << ','
               << format_g(g.build_max, 8) << ','
               << format_g(g.kernels ? g.kernel_rms_sum / g.kernels : 0, 8) << ','
               << format_g(g.l1_error_max, 8) << ','
               << (g.images ? format_g(g.image_rms_sum / g.images, 8) : "") << ','
               << (g.taps_images ? format_g(g.taps_rms_sum / g.taps_images, 8) : "") << '\n';
        }
        return pr.str();
    }
};

}  // namespace

std::map<std::string, std::string> run_kernel_study(
    const KernelStudySpec& spec, const std::map<std::string, RadialProfile>& profiles,
    std::string& summary) {
    KernelStudyRun run(spec);
    const auto t0 = Clock::now();
    for (const auto& material : spec.materials) run.add_material(material, profiles.at(material));
    std::map<std::string, std::string> files = run.files();
    std::ostringstream sum;
    sum << spec.materials.size() << " materials x " << spec.models.size() << " models";
    if (!spec.signals.empty()) sum << " x " << spec.signals.size() << " signals";
    char secs[32];
    std::snprintf(secs, sizeof secs, "%.3g",
                  std::chrono::duration<double>(Clock::now() - t0).count());
    sum << " in " << secs << " s";
    summary = sum.str();
    return files;
}

}  // namespace ssslab::runner
