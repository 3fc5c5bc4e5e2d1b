#include "volpath/density_grid.h"

#include "core/error.h"

#include <cmath>
#include <filesystem>

#ifdef SSSLAB_HAVE_OPENVDB
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>
#endif

namespace ssslab::volpath {

#ifdef SSSLAB_HAVE_OPENVDB

namespace {

class VdbDensity final : public DensityGrid {
  public:
    explicit VdbDensity(openvdb::FloatGrid::ConstPtr g, double max)
        : grid_(std::move(g)), max_(max) {}
    double density(const Vec3& p) const override {
        // An accessor per call (accessors are not thread-safe; reading the tree is). It must
        // outlive the sampler, which keeps a reference to it.
        const openvdb::FloatGrid::ConstAccessor acc = grid_->getConstAccessor();
        float v = 0;
        openvdb::tools::BoxSampler::sample(
            acc, grid_->transform().worldToIndex(openvdb::Vec3d(p.x, p.y, p.z)), v);
        return v;
    }
    double max_density() const override { return max_; }

  private:
    openvdb::FloatGrid::ConstPtr grid_;
    double max_;
};

}  // namespace

bool DensityGrid::available() {
    return true;
}

std::shared_ptr<const DensityGrid> DensityGrid::load(const std::string& path,
                                                     const std::string& grid_name) {
    openvdb::initialize();
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
        throw InputError({path, 0, 0}, "", "OpenVDB file not found");
    openvdb::GridBase::Ptr base;
    try {
        openvdb::io::File file(path);
        file.open();
        if (!file.hasGrid(grid_name)) {
            std::string names;
            for (auto it = file.beginName(); it != file.endName(); ++it)
                names += (names.empty() ? "" : ", ") + it.gridName();
            file.close();
            throw InputError({path, 0, 0}, "",
                             "no grid named \"" + grid_name +
                                 "\" (the file has: " + (names.empty() ? "none" : names) + ")");
        }
        base = file.readGrid(grid_name);
        file.close();
    } catch (const openvdb::Exception& e) {
        throw InputError({path, 0, 0}, "", std::string("OpenVDB: ") + e.what());
    }
    openvdb::FloatGrid::Ptr g = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
    if (!g)
        throw InputError({path, 0, 0}, "",
                         "grid \"" + grid_name + "\" is a " + base->valueType() +
                             " grid; a float grid is needed");
    double lo = g->background(), hi = g->background();
    for (auto it = g->cbeginValueOn(); it; ++it) {
        const double v = *it;
        lo = std::min(lo, v);
        hi = std::max(hi, v);
        if (!std::isfinite(v)) break;
    }
    if (!std::isfinite(lo) || !std::isfinite(hi) || lo < 0)
        throw InputError({path, 0, 0}, "",
                         "grid \"" + grid_name + "\" has negative or non-finite densities (min " +
                             std::to_string(lo) + ")");
    if (!(hi > 0))
        throw InputError({path, 0, 0}, "", "grid \"" + grid_name + "\" is zero everywhere");
    return std::make_shared<VdbDensity>(g, hi);
}

#else

bool DensityGrid::available() {
    return false;
}

std::shared_ptr<const DensityGrid> DensityGrid::load(const std::string& path, const std::string&) {
    throw InputError({path, 0, 0}, "",
                     "this build has no OpenVDB (configure with SSSLAB_WITH_OPENVDB=ON after "
                     "apt-get install libopenvdb-dev libboost-iostreams-dev)");
}

#endif

}  // namespace ssslab::volpath
