#include "experiments/runner/nodes.h"

#include "volpath/pencil.h"

namespace ssslab::runner {

const ChannelNode* find_node(const ExperimentRun& r, const std::string& material, int c,
                             const std::string& role) {
    for (const auto& n : r.nodes)
        if (n.material == material && n.channel == c && n.role == role) return &n;
    return nullptr;
}

RadialProfile volpath_profile(const ExperimentRun& r, const std::string& material, bool single) {
    RadialProfile p;
    p.name = material;
    for (int c = 0; c < 3; ++c) {
        const ChannelNode* n = find_node(r, material, c, "volpath");
        volpath::fill_profile(n->vresult, 0, {n->grid.dr_cm, n->grid.nr}, c,
                              volpath::entry_specular(n->medium), p, single);
    }
    return p;
}

RadialProfile material_profile(const ExperimentRun& r, const std::string& material) {
    RadialProfile p;
    p.name = material;
    for (int c = 0; c < 3; ++c) {
        const ChannelNode* n = find_node(r, material, c, "main");
        p.dr_cm = n->grid.dr_cm;
        p.nr = n->grid.nr;
        mcml::fill_profile(n->result, n->grid, c, p);
    }
    return p;
}

}  // namespace ssslab::runner
