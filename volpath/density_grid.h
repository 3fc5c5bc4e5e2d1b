// Heterogeneous media: a density field read from an OpenVDB grid [Museth 2013] (optional build
// part: SSSLAB_WITH_OPENVDB, Debian's libopenvdb-dev). The density d(x) >= 0 scales a medium's
// sigma_a and sigma_s alike (so the albedo stays constant), sampled trilinearly in the grid's
// own world space (its transform from the file, in the scene's world unit). The path tracer
// tracks it by delta tracking against the majorant sigma_t max(d) [Woodcock et al. 1965]:
// tentative collisions at the majorant's rate, real with probability d(x) / max(d).
//
// Opened only for scenes that reference a .vdb file; without OpenVDB in the build, loading
// throws an InputError that says so.
#pragma once

#include "core/vec3.h"

#include <memory>
#include <string>

namespace ssslab::volpath {

class DensityGrid {
  public:
    /// Read float grid `grid_name` of a .vdb file. Throws InputError naming the file for a
    /// missing file or grid, a grid that is not a float grid, a negative or non-finite value,
    /// or an empty grid; and when this build has no OpenVDB.
    static std::shared_ptr<const DensityGrid> load(const std::string& path,
                                                   const std::string& grid_name);
    virtual ~DensityGrid() = default;

    /// Trilinear density at a world point (the background value outside the active voxels).
    virtual double density(const Vec3& p) const = 0;
    /// An upper bound of density() everywhere (the maximum over active voxels and background).
    virtual double max_density() const = 0;

    /// Whether this build can read .vdb files.
    static bool available();
};

}  // namespace ssslab::volpath
