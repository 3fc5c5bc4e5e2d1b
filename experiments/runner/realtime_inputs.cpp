#include "experiments/runner/realtime_inputs.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace ssslab::runner {

RealtimeInputOptions::RealtimeInputOptions() {
    profile_budget.samples = 1'000'000;
    slab_budget.samples = 100'000;
    run.quiet = true;
}

std::vector<double> slab_thicknesses(double min_mm, double max_mm, int n) {
    if (!(min_mm > 0) || !(max_mm > min_mm) || n < 2)
        throw std::invalid_argument("slab_thicknesses: need 0 < min < max and n >= 2");
    std::vector<double> t(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i)
        t[static_cast<size_t>(i)] = min_mm * std::pow(max_mm / min_mm, i / (n - 1.0));
    return t;
}

namespace {

std::string label_of(const Scene& s, int m) {
    return "m" + std::to_string(m) + "." + s.materials[static_cast<size_t>(m)].name;
}

std::string slab_label(const Scene& s, int m, size_t k) {
    return label_of(s, m) + "@" + std::to_string(k);
}

}  // namespace

RealtimeInputs realtime_inputs(const Scene& scene, const std::vector<int>& materials,
                               const RealtimeInputOptions& o) {
    RealtimeInputs out;
    Experiment prof, slab;
    prof.name = slab.name = "realtime-inputs";
    prof.seed = slab.seed = o.seed;
    prof.mcml.budget = o.profile_budget;
    slab.mcml.budget = o.slab_budget;
    std::vector<int> media;
    for (int m : materials) {
        if (m < 0 || m >= static_cast<int>(scene.materials.size())) continue;
        const SceneMaterial& sm = scene.materials[static_cast<size_t>(m)];
        if (sm.kind != SceneMaterial::Kind::kMedium) continue;
        media.push_back(m);
        prof.materials.push_back({label_of(scene, m), sm.medium});
        for (size_t k = 0; k < o.slab_thickness_mm.size(); ++k) {
            Medium thin = sm.medium;
            thin.thickness_cm = o.slab_thickness_mm[k] / 10.0;
            slab.materials.push_back({slab_label(scene, m, k), thin});
        }
    }
    RunOptions ro = o.run;
    ro.quick = false;
    for (Experiment* e : {&prof, &slab}) {
        if (e->materials.empty()) continue;
        ExperimentRun r = plan(*e, ro);
        if (!compute_nodes(r, ro)) {
            out.interrupted = true;
            return out;
        }
        out.computed += r.computed;
        out.reused += r.reused;
        for (int m : media) {
            if (e == &prof) {
                out.profiles[m] = material_profile(r, label_of(scene, m));
                // The preset's name where there is one (Table A.1 rows are by preset).
                const SceneMaterial& sm = scene.materials[static_cast<size_t>(m)];
                out.profiles[m].name = sm.preset.empty() ? sm.name : sm.preset;
                continue;
            }
            SlabTable& t = out.slabs[m];
            for (size_t k = 0; k < o.slab_thickness_mm.size(); ++k) {
                std::array<double, 3> v{}, se{};
                for (int c = 0; c < 3; ++c) {
                    const ChannelNode* n = find_node(r, slab_label(scene, m, k), c, "main");
                    const size_t i = n->result.layout.tt;
                    v[static_cast<size_t>(c)] = n->result.mean(i);
                    se[static_cast<size_t>(c)] = n->result.se[i];
                }
                t.thickness_mm.push_back(o.slab_thickness_mm[k]);
                t.transmittance.push_back(v);
                t.se.push_back(se);
            }
        }
    }
    return out;
}

}  // namespace ssslab::runner
