#include "experiments/runner/experiment.h"
#include "experiments/runner/study.h"

#include "approx/diffusion.h"
#include "core/error.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <set>

namespace ssslab::runner {

namespace {

// [materials]: presets by name and [[materials.custom]] tables, their labels unique.
void read_materials(ConfigTable& mats, Experiment& e, std::set<std::string>& labels) {
    if (mats.has("presets")) {
        auto presets = mats.string_list("presets");
        for (size_t i = 0; i < presets.size(); ++i) {
            auto m = find_material(presets[i]);
            if (!m) mats.fail_item("presets", i, unknown_material_message(presets[i]));
            if (!labels.insert(m->name).second)
                mats.fail_item("presets", i, "material \"" + m->name + "\" is listed twice");
            e.materials.push_back({m->name, *m});
        }
    }
    for (ConfigTable& c : mats.table_array("custom")) {
        const std::string label = c.string("name");
        if (label.empty() || label.find_first_of("/\\ \t\n\"'<>&") != std::string::npos)
            c.fail("name", "expected a material name without spaces, slashes or quotes");
        Medium m = medium_from_config(c);
        m.name = label;
        if (!labels.insert(label).second)
            c.fail("name", "material \"" + label + "\" is defined twice");
        e.materials.push_back({label, m});
    }
}

// [mcml] (the ground truth's budget, batches and grid) and [volpath] (the second engine, when
// an output compares with it).
void read_engines(ConfigTable& root, Experiment& e) {
    ConfigTable mc = root.table_or_empty("mcml");
    e.mcml.budget = mcml::read_budget(mc);
    if (!e.mcml.budget.any()) {
        e.mcml.budget.samples = mcml::kFreude14Photons;
        mc.record("photons", static_cast<std::int64_t>(mcml::kFreude14Photons));
    }
    e.mcml.quick_factor = mc.number("quick_factor", 0.02, Range::left_open(0, 1));
    e.mcml.batch_photons = mc.integer("batch_photons", 0, Range::nonnegative());
    ConfigTable grid = mc.table_or_empty("grid");
    e.mcml.grid = mcml::read_grid_override(grid);

    if (auto vp = root.table("volpath")) {
        e.volpath.enabled = true;
        e.volpath.budget = mcml::read_budget(*vp);
        if (!e.volpath.budget.any()) {
            e.volpath.budget.samples = 1'000'000;
            vp->record("photons", static_cast<std::int64_t>(1'000'000));
        }
        e.volpath.quick_factor = vp->number("quick_factor", 0.02, Range::left_open(0, 1));
        e.volpath.batch_paths = vp->integer("batch_paths", 0, Range::nonnegative());
        e.volpath.mode = vp->choice("mode", "analog", {"analog", "weighted"});
    }
}

Experiment parse(std::shared_ptr<ConfigDocument> doc) {
    Experiment e;
    e.doc = doc;
    e.source = doc->name();
    ConfigTable root = doc->root();

    ConfigTable ex = root.require_table("experiment");
    e.name = ex.string("name");
    if (e.name.empty() ||
        e.name.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789-_.") != std::string::npos ||
        e.name[0] == '.')
        ex.fail("name",
                "expected a name of lower-case letters, digits, '-', '_' and '.' (it names the "
                "results directory), got \"" +
                    e.name + "\"");
    e.title = ex.string("title", e.name);
    e.description = ex.string("description", "");
    e.seed = static_cast<std::uint64_t>(ex.integer("seed", 1, Range::nonnegative()));

    ConfigTable mats = root.table_or_empty("materials");
    std::set<std::string> labels;
    read_materials(mats, e, labels);

    read_engines(root, e);

    ConfigTable outs = root.require_table("outputs");
    auto need_volpath = [&](ConfigTable& t, const char* what) {
        if (!e.volpath.enabled)
            t.fail("enabled", std::string(what) +
                                  " compares with the path tracer: add a [volpath] table (its "
                                  "budget per channel, e.g. photons = 1e6)");
    };
    if (auto t = outs.table("crossval")) {
        e.crossval.enabled = true;
        e.crossval.max_rel_se = t->number("max_rel_se", 0.3, Range::left_open(0, 1));
        need_volpath(*t, "[outputs.crossval]");
    }
    if (auto t = outs.table("pencil")) {
        e.pencil.enabled = true;
        const std::vector<std::string> entries = t->string_list("models");
        const std::string base = std::filesystem::path(e.source).parent_path().string();
        for (size_t i = 0; i < entries.size(); ++i) {
            try {
                e.pencil.models.add(entries[i], base);
            } catch (const std::invalid_argument& x) {
                t->fail_item("models", i, x.what());
            }
        }
        if (entries.empty()) t->fail("models", "expected at least one diffusion model");
        if (auto pt = t->table("parameters")) e.pencil.models.read_parameters(*pt);
        for (const MaterialEntry& m : e.materials)
            if (m.medium.layered())
                t->fail("models", "the diffusion models describe homogeneous slabs; material \"" +
                                      m.label + "\" is layered (" +
                                      std::to_string(1 + m.medium.lower_layers.size()) +
                                      " layers): put it in an experiment without [outputs.pencil]");
        need_volpath(*t, "[outputs.pencil]");
    }
    if (auto t = outs.table("efficiency")) {
        e.efficiency.enabled = true;
        e.efficiency.materials = t->string_list("materials");
        if (e.efficiency.materials.empty())
            t->fail("materials", "expected at least one material of this experiment");
        for (size_t i = 0; i < e.efficiency.materials.size(); ++i)
            if (!labels.count(e.efficiency.materials[i]))
                t->fail_item(
                    "materials", i,
                    "\"" + e.efficiency.materials[i] + "\" is not a material of this experiment");
        need_volpath(*t, "[outputs.efficiency]");
    }
    if (auto t = outs.table("profiles")) {
        e.profiles.enabled = true;
        e.profiles.unit = t->enumerated("unit", LengthUnit::kMm);
    }
    if (auto t = outs.table("profile_plots")) {
        e.profile_plots.enabled = true;
        e.profile_plots.linear_range_mfp =
            t->number("linear_range_mfp", 2.0, Range::left_open(0, 1e4));
    }
    if (auto t = outs.table("convergence")) {
        e.convergence.enabled = true;
        e.convergence.materials = t->string_list("materials");
        if (e.convergence.materials.empty())
            t->fail("materials", "expected at least one material of this experiment");
        for (size_t i = 0; i < e.convergence.materials.size(); ++i)
            if (!labels.count(e.convergence.materials[i]))
                t->fail_item(
                    "materials", i,
                    "\"" + e.convergence.materials[i] + "\" is not a material of this experiment");
        e.convergence.reference_factor =
            t->number("reference_factor", 4.0, Range::closed(1.0, 1000.0));
        if (!e.mcml.budget.samples)
            t->fail("materials",
                    "a convergence study needs a photon budget in [mcml] (the reference run has "
                    "reference_factor times as many photons)");
    }
    {
        std::vector<std::string> all_labels;
        for (const auto& m : e.materials) all_labels.push_back(m.label);
        std::set<std::string> names;
        for (ConfigTable& t : outs.table_array("kernels")) {
            e.kernel_studies.push_back(read_kernel_study(t, all_labels));
            if (!names.insert(e.kernel_studies.back().name).second)
                t.fail("name", "a kernel study named \"" + e.kernel_studies.back().name +
                                   "\" is defined twice");
        }
    }
    for (const auto& [name, factory] : study_registry())
        if (auto t = outs.table(name))
            e.studies.push_back(
                {name, factory(*t, std::filesystem::path(e.source).parent_path().string())});
    const bool material_outputs = e.profiles.enabled || e.profile_plots.enabled ||
                                  e.convergence.enabled || !e.kernel_studies.empty() ||
                                  e.crossval.enabled || e.pencil.enabled || e.efficiency.enabled;
    if (!material_outputs && e.studies.empty()) {
        std::string plugins;
        for (const auto& [name, factory] : study_registry()) plugins += ", [outputs." + name + "]";
        outs.fail("profiles",
                  "no outputs: give at least one of [outputs.profiles], "
                  "[outputs.profile_plots], [outputs.convergence], [[outputs.kernels]], "
                  "[outputs.crossval], [outputs.pencil], [outputs.efficiency]" +
                      plugins);
    }
    if (material_outputs && e.materials.empty())
        mats.fail("presets", "no materials: give presets = [...] or [[materials.custom]] tables");
    if (!material_outputs && !e.materials.empty())
        mats.fail("presets",
                  "no output of this experiment reads materials ([outputs.render] and "
                  "[outputs.realtime] take them from their scenes, [outputs.stiff] has its "
                  "own): remove [materials]");
    root.finish();
    return e;
}

}  // namespace

Experiment read_experiment(const std::string& path) {
    return parse(ConfigDocument::parse_file(path));
}

Experiment parse_experiment(std::string_view text, const std::string& name) {
    return parse(ConfigDocument::parse_string(text, name));
}

}  // namespace ssslab::runner
