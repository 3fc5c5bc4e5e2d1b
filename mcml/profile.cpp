#include "mcml/profile.h"

#include "core/config.h"
#include "mcml/transport.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ssslab::mcml {

ProfileGrid freude14_grid(const Medium& m) {
    // Layered media: the finest bins any (non-clear) layer needs, the extent the widest needs.
    double mfp_min = std::numeric_limits<double>::infinity(), mfp_max = 0;
    for (const MediumLayer& l : m.layers()) {
        if (l.clear()) continue;
        for (int c = 0; c < 3; ++c) {
            mfp_min = std::min(mfp_min, l.mfp_cm(c));
            mfp_max = std::max(mfp_max, l.mfp_cm(c));
        }
    }
    if (!(mfp_max > 0)) mfp_min = mfp_max = m.mfp_cm(0);  // all clear: refused by check_run
    ProfileGrid g;
    g.dr_cm = mfp_min / 20.0;
    g.nr = static_cast<int>(std::ceil(32.0 * mfp_max / g.dr_cm));
    return g;
}

GridOverride read_grid_override(ConfigTable& t) {
    GridOverride o;
    o.dr_cm = optional_length_cm(t, "dr", Range::positive());
    if (auto v = t.optional_integer("nr", Range::closed(1, 1e7))) o.nr = static_cast<int>(*v);
    return o;
}

SampleBudget read_budget(ConfigTable& t) {
    SampleBudget b;
    b.samples = t.optional_integer("photons", Range::closed(1, 9e18));
    b.seconds = t.optional_number("seconds", Range::positive());
    b.rel_error = t.optional_number("rel_error", Range::open(0, 1));
    return b;
}

void fill_profile(const RunResult& r, const ProfileGrid& grid, int c, RadialProfile& p) {
    const TallyLayout& L = r.layout;
    p.rd_per_cm2[c].resize(static_cast<size_t>(grid.nr));
    p.se_per_cm2[c].resize(static_cast<size_t>(grid.nr));
    for (int i = 0; i < grid.nr; ++i) {
        const double area = 2.0 * kPi * (i + 0.5) * grid.dr_cm * grid.dr_cm;
        p.rd_per_cm2[c][static_cast<size_t>(i)] = r.mean(L.rd_r + static_cast<size_t>(i)) / area;
        p.se_per_cm2[c][static_cast<size_t>(i)] = r.se[L.rd_r + static_cast<size_t>(i)] / area;
    }
    p.rd_total[c] = r.mean(L.rd);
    p.rd_total_se[c] = r.se[L.rd];
    p.beyond[c] = r.mean(L.rd_r + static_cast<size_t>(grid.nr));
    p.beyond_se[c] = r.se[L.rd_r + static_cast<size_t>(grid.nr)];
    p.rsp[c] = r.rsp;
}

ProfileRun simulate_profile(const Medium& m, const ProfileGrid& grid, const ProfileOptions& o) {
    ProfileRun out;
    out.medium = m;
    out.grid = grid;
    out.profile.name = m.name;
    out.profile.dr_cm = grid.dr_cm;
    out.profile.nr = grid.nr;
    Grid g;
    g.dr = grid.dr_cm;
    g.nr = grid.nr;
    g.dz = m.total_thickness_cm();  // unused by profile tallies
    g.nz = 1;
    g.na = 1;
    for (int c = 0; c < 3; ++c) {
        const std::int64_t photons = kFreude14Photons;
        RunSpec run = run_for_channel(m, c, photons, g);
        EngineOptions eo;
        static_cast<RunControl&>(eo) = o;
        eo.stream = static_cast<std::uint64_t>(c);
        eo.batch_photons = o.batch_photons;
        eo.mode = TallyMode::kProfile;
        if (!o.checkpoint_prefix.empty())
            eo.checkpoint_path = run_checkpoint_path(o.checkpoint_prefix, kChannelNames[c]);
        if (o.on_batch) eo.on_batch = [&o, c](const BatchProgress& p) { o.on_batch(c, p); };
        if (o.on_resume)
            eo.on_resume = [&o, c, path = eo.checkpoint_path](const BatchProgress& p) {
                o.on_resume(c, p, path);
            };
        out.channels[c] = run_default(run, eo);
        if (out.channels[c].reason == BatchStop::kInterrupted) {
            out.interrupted = true;
            return out;
        }
        fill_profile(out.channels[c], grid, c, out.profile);
    }
    return out;
}

}  // namespace ssslab::mcml
