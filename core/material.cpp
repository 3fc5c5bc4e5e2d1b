#include "core/material.h"

#include "core/config.h"
#include "core/hash.h"

#include <algorithm>
#include <cctype>
#include <stdexcept>

namespace ssslab {

namespace {

Medium make(const char* name, std::array<double, 3> sa, std::array<double, 3> ss, double eta) {
    Medium m;
    m.name = name;
    m.sigma_a_per_cm = sa;
    m.sigma_s_per_cm = ss;
    m.g = {0.0, 0.0, 0.0};
    m.eta = eta;
    m.thickness_cm = 1e8;
    return m;
}

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return s;
}

}  // namespace

const std::vector<MaterialPreset>& freude14_materials() {
    // [Freude14 Table 6.2], sigma in 1/cm, g = 0, thickness 1e8 cm.
    static const char* kSrc = "Freude14 Table 6.2 (Jensen et al. 2001), 1/cm";
    static const std::vector<MaterialPreset> presets = {
        {"Apple", make("Apple", {0.03, 0.034, 0.46}, {22.9, 23.9, 19.7}, 1.3), kSrc},
        {"Chicken1", make("Chicken1", {0.15, 0.77, 1.9}, {1.5, 2.1, 3.8}, 1.3), kSrc},
        {"Chicken2", make("Chicken2", {0.18, 0.88, 2.0}, {1.9, 2.5, 3.2}, 1.3), kSrc},
        {"Cream", make("Cream", {0.002, 0.028, 0.163}, {73.8, 54.7, 31.5}, 1.3), kSrc},
        {"Ketchup", make("Ketchup", {0.61, 9.7, 14.5}, {1.8, 0.7, 0.3}, 1.3), kSrc},
        {"Marble", make("Marble", {0.021, 0.041, 0.071}, {21.9, 26.2, 30.0}, 1.5), kSrc},
        {"Potato", make("Potato", {0.024, 0.09, 1.2}, {6.8, 7.0, 5.5}, 1.3), kSrc},
        {"Skimmilk", make("Skimmilk", {0.014, 0.025, 0.142}, {7.0, 12.2, 19.0}, 1.3), kSrc},
        {"Skin1", make("Skin1", {0.32, 1.7, 4.8}, {7.4, 8.8, 10.1}, 1.3), kSrc},
        {"Skin2", make("Skin2", {0.13, 0.7, 1.45}, {10.9, 15.9, 17.9}, 1.3), kSrc},
        {"Wholemilk", make("Wholemilk", {0.011, 0.024, 0.14}, {25.5, 32.1, 37.7}, 1.3), kSrc},
    };
    return presets;
}

const std::vector<std::string>& freude14_main_materials() {
    static const std::vector<std::string> names = {"Apple", "Marble", "Ketchup", "Skin1",
                                                   "Wholemilk"};
    return names;
}

std::optional<Medium> find_material(const std::string& name) {
    const std::string key = lower(name);
    for (const auto& p : freude14_materials())
        if (lower(p.name) == key) return p.medium;
    return std::nullopt;
}

std::string material_names() {
    std::string s;
    for (const auto& p : freude14_materials()) s += (s.empty() ? "" : ", ") + std::string(p.name);
    return s;
}

namespace {

// The preset name nearest to `name` (edit distance at most 3), or "" if none is near.
std::string nearest_material(const std::string& name) {
    std::string best;
    int best_d = 1 << 30;
    for (const auto& q : freude14_materials()) {
        const int d = edit_distance(lower(name), lower(q.name));
        if (d < best_d) best_d = d, best = q.name;
    }
    return best_d <= 3 ? best : std::string();
}

}  // namespace

std::string unknown_material_message(const std::string& name) {
    std::string msg = "unknown material \"" + name + "\"";
    const std::string near = nearest_material(name);
    if (!near.empty()) msg += " (did you mean \"" + near + "\"?)";
    return msg + "; known materials: " + material_names();
}

namespace {

// Read a length-dependent RGB quantity given either per mm or per cm; returns it per cm.
std::optional<std::array<double, 3>> coefficient_per_cm(ConfigTable& t, const std::string& base) {
    const std::string mm = base + "_per_mm", cm = base + "_per_cm";
    if (t.has(mm) && t.has(cm)) t.fail(cm, "give " + base + " once, per mm or per cm, not both");
    if (auto v = t.optional_rgb(mm, Range::nonnegative())) {
        for (double& x : *v) x *= 10.0;  // 1/mm -> 1/cm
        return v;
    }
    return t.optional_rgb(cm, Range::nonnegative());
}

}  // namespace

std::optional<double> optional_length_cm(ConfigTable& t, const std::string& base, const Range& r) {
    const std::string mm = base + "_mm", cm = base + "_cm";
    if (t.has(mm) && t.has(cm)) t.fail(cm, "give " + base + " once, in mm or in cm, not both");
    if (auto v = t.optional_number(mm, r)) return *v / 10.0;
    return t.optional_number(cm, r);
}

namespace {

constexpr const char* kLayerKeys[] = {
    "preset", "sigma_a_per_mm", "sigma_a_per_cm", "sigma_s_per_mm", "sigma_s_per_cm", "g",
    "eta",    "thickness_mm",   "thickness_cm"};

// The coefficients and index of one homogeneous slab: a preset or explicit coefficients (and
// its thickness, if `with_thickness`).
Medium read_homogeneous(ConfigTable& t, bool with_thickness = true) {
    Medium m;
    const bool explicit_coeffs = t.has("sigma_a_per_mm") || t.has("sigma_a_per_cm") ||
                                 t.has("sigma_s_per_mm") || t.has("sigma_s_per_cm");
    if (t.has("preset")) {
        const std::string name = t.string("preset");
        auto p = find_material(name);
        if (!p) t.fail("preset", unknown_material_message(name));
        if (explicit_coeffs)
            t.fail("preset", "give either a preset or explicit coefficients, not both");
        m = *p;
    } else {
        if (!explicit_coeffs)
            t.fail("preset",
                   "expected `preset = \"<name>\"` (one of " + material_names() +
                       ") or explicit sigma_a_per_mm/_per_cm, sigma_s_per_mm/_per_cm, g, eta");
        auto sa = coefficient_per_cm(t, "sigma_a");
        auto ss = coefficient_per_cm(t, "sigma_s");
        if (!sa) t.fail("sigma_a_per_mm", "missing: sigma_a_per_mm or sigma_a_per_cm (RGB)");
        if (!ss) t.fail("sigma_s_per_mm", "missing: sigma_s_per_mm or sigma_s_per_cm (RGB)");
        m.sigma_a_per_cm = *sa;
        m.sigma_s_per_cm = *ss;
        m.g = t.optional_rgb("g", Range::closed(-1.0, 1.0)).value_or(std::array<double, 3>{});
        m.eta = t.number("eta", Range::positive());
        m.thickness_cm = 1e8;
    }
    if (with_thickness)
        if (auto d = optional_length_cm(t, "thickness", Range::positive())) m.thickness_cm = *d;
    return m;
}

}  // namespace

Medium medium_coefficients_from_config(ConfigTable& t) {
    Medium m = read_homogeneous(t, false);
    if (!t.has("preset")) m.name.clear();
    return m;
}

std::vector<MediumLayer> Medium::layers() const {
    std::vector<MediumLayer> out;
    out.reserve(1 + lower_layers.size());
    out.push_back({sigma_a_per_cm, sigma_s_per_cm, g, eta, thickness_cm});
    out.insert(out.end(), lower_layers.begin(), lower_layers.end());
    return out;
}

double Medium::total_thickness_cm() const {
    double d = thickness_cm;
    for (const MediumLayer& l : lower_layers) d += l.thickness_cm;
    return d;
}

void require_homogeneous(const Medium& m, const std::string& what) {
    if (m.layered())
        throw std::invalid_argument(what + " needs a homogeneous medium; \"" + m.name + "\" has " +
                                    std::to_string(1 + m.lower_layers.size()) + " layers");
}

Medium medium_from_config(ConfigTable& t) {
    if (t.has("layers")) {
        for (const char* k : kLayerKeys)
            if (t.has(k))
                t.fail(k, std::string("a layered medium gives ") + k +
                              " per layer: move it into its [[layers]] table");
        std::vector<ConfigTable> ls = t.table_array("layers");
        if (ls.empty()) t.fail("layers", "expected at least one [[layers]] table");
        Medium m;
        m.name = t.string("name", "layered");
        for (size_t i = 0; i < ls.size(); ++i) {
            ConfigTable& l = ls[i];
            const bool has_thickness = l.has("thickness_mm") || l.has("thickness_cm");
            const Medium one = read_homogeneous(l);
            if (i + 1 < ls.size() && !has_thickness)
                l.fail("thickness_mm",
                       "missing: every layer but the last needs thickness_mm or thickness_cm");
            if (i + 1 < ls.size() && one.thickness_cm >= 1e8)
                l.fail(l.has("thickness_mm") ? "thickness_mm" : "thickness_cm",
                       "only the last layer may be quasi-infinite (>= 1e8 cm)");
            l.record("thickness_cm", one.thickness_cm);
            if (i == 0) {
                m.sigma_a_per_cm = one.sigma_a_per_cm;
                m.sigma_s_per_cm = one.sigma_s_per_cm;
                m.g = one.g;
                m.eta = one.eta;
                m.thickness_cm = one.thickness_cm;
            } else {
                m.lower_layers.push_back(
                    {one.sigma_a_per_cm, one.sigma_s_per_cm, one.g, one.eta, one.thickness_cm});
            }
        }
        m.eta_above = t.number("eta_above", 1.0, Range::positive());
        m.eta_below = t.number("eta_below", 1.0, Range::positive());
        return m;
    }
    Medium m = read_homogeneous(t);
    if (!t.has("preset")) m.name = t.string("name", "custom");
    m.eta_above = t.number("eta_above", 1.0, Range::positive());
    m.eta_below = t.number("eta_below", 1.0, Range::positive());
    t.record("thickness_cm", m.thickness_cm);
    return m;
}

void add_to_key(ContentKey& k, const std::string& prefix, const Medium& m) {
    k.add(prefix + "sigma_a_per_cm", m.sigma_a_per_cm)
        .add(prefix + "sigma_s_per_cm", m.sigma_s_per_cm)
        .add(prefix + "g", m.g)
        .add(prefix + "eta", m.eta)
        .add(prefix + "eta_above", m.eta_above)
        .add(prefix + "eta_below", m.eta_below)
        .add(prefix + "thickness_cm", m.thickness_cm);
    for (std::size_t i = 0; i < m.lower_layers.size(); ++i) {
        const MediumLayer& l = m.lower_layers[i];
        const std::string p = prefix + "layers[" + std::to_string(i + 1) + "].";
        k.add(p + "sigma_a_per_cm", l.sigma_a_per_cm)
            .add(p + "sigma_s_per_cm", l.sigma_s_per_cm)
            .add(p + "g", l.g)
            .add(p + "eta", l.eta)
            .add(p + "thickness_cm", l.thickness_cm);
    }
}

void record_simulated(ConfigTable& t, const Medium& m) {
    auto rgb = [](const std::array<double, 3>& v) {
        return std::vector<double>(v.begin(), v.end());
    };
    if (!m.name.empty()) t.record("name", m.name);
    std::vector<std::vector<double>> sa, ss, g;
    std::vector<double> eta, thickness;
    for (const MediumLayer& l : m.layers()) {
        sa.push_back(rgb(l.sigma_a_per_cm));
        ss.push_back(rgb(l.sigma_s_per_cm));
        g.push_back(rgb(l.g));
        eta.push_back(l.eta);
        thickness.push_back(l.thickness_cm);
    }
    t.record("sigma_a_per_cm", sa);
    t.record("sigma_s_per_cm", ss);
    t.record("g", g);
    t.record("eta", eta);
    t.record("thickness_cm", thickness);
    t.record("eta_above", m.eta_above);
    t.record("eta_below", m.eta_below);
    t.record("boundary", std::string("smooth dielectric (Fresnel) at every interface"));
}

}  // namespace ssslab
