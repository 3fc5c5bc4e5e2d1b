// Models named in experiment configs: "svd:rank=3", "svd:rank=1,l1", "preintegration",
// "guided:k=1", "guided:k=1.55,b=50", "manual:table_a1,unit=mm", "manual:fit=skin_shaded",
// "deon:n=4", "ssss_skin". One table maps names to factories; the built-in models are entries of
// it like any other, and a program that links ssslab adds its own with register_model (see
// examples/custom_model/). An unknown name or key is an error that lists what exists.
#pragma once

#include "approx/image.h"
#include "approx/kernel2d.h"
#include "approx/models.h"

#include <functional>
#include <map>
#include <string>
#include <vector>

namespace ssslab::approx {

struct ModelSpec {
    std::string text;  ///< as written, e.g. "guided:k=1"
    std::string name;  ///< a factory's name: "svd", "preintegration", "guided", ...
    std::map<std::string, std::string> params;

    double number(const std::string& key, double fallback) const;
    std::string string(const std::string& key, const std::string& fallback) const;
    bool flag(const std::string& key) const { return params.count(key) > 0; }
    /// A short label for tables and file names, e.g. "svd3", "guided_k1", "manual_a1_mm".
    std::string label() const;
    /// Properties for Table 5.1.
    bool closed_form() const;  ///< no optimisation needed to build it
    /// The text and, for a model registered from outside, its factory's version: what a cache
    /// key holds of the model (the built-in models' numbers are versioned by their studies).
    std::string cache_text() const;
};

/// Parse and validate a model spec; throws std::invalid_argument with a message naming the
/// offending part and listing the valid names and keys.
ModelSpec parse_model(const std::string& text);

/// What the builders need besides the kernel: the material (Table A.1 is per material), the
/// channel, and for image-space fits the test signal machinery.
struct ModelContext {
    std::string material;
    int channel = 0;
    /// For image-space fits ("manual:fit=SIGNAL"): a test signal and its exact 2D convolution
    /// with the material's kernels, on the study's pixel grid.
    std::function<const std::pair<ImageRGB, ImageRGB>&(Signal)> fit_images;
};

/// Build a model for one channel.
ModelResult build_model(const ModelSpec& spec, const Kernel2D& k, const ModelContext& ctx);

/// One entry of the name -> factory table.
struct ModelFactory {
    std::string name;               ///< what configs write before the ':' ([a-z0-9_]+)
    std::vector<std::string> keys;  ///< the parameters it takes ("rank", "l1", ...)
    std::string help;               ///< one line for error messages, e.g. "svd:rank=N[,l1] (...)"
    /// Part of every cache key of a study that scores the model: change it whenever the model's
    /// numbers change. Required for models registered from outside; empty for the built-ins.
    std::string version;
    /// Whether spec builds without optimisation (Table 5.1); null: true.
    std::function<bool(const ModelSpec&)> closed_form;
    /// Checks the parameters' values at parse time (throws std::invalid_argument naming the
    /// spec); null: any values.
    std::function<void(const ModelSpec&)> validate;
    /// Builds one channel: a separable kernel on k's grid (kernel.h_mm and kernel.n as k's).
    std::function<ModelResult(const ModelSpec&, const Kernel2D&, const ModelContext&)> build;
};

/// Add a model to the table, before any config naming it is read. Throws std::invalid_argument
/// for a name that is taken or not [a-z0-9_]+, a missing build function or version, or a key
/// that is not [a-z0-9_]+.
void register_model(ModelFactory factory);

/// The names in the table, sorted.
std::vector<std::string> model_names();

/// The manual model's parameters of [Freude14 Table A.1] (sqrt(tau) per channel, w), for
/// Apple, Ketchup, Marble, Skin1, Wholemilk; the unit is not stated in the thesis.
struct TableA1Row {
    std::array<double, 3> sqrt_tau_near, sqrt_tau_far;
    double w;
};
const std::map<std::string, TableA1Row>& freude14_table_a1();

}  // namespace ssslab::approx
