#include "volpath/radiance_grid.h"

#include <algorithm>
#include <cmath>

namespace ssslab::volpath {

RadianceGrid::RadianceGrid(const Vec3& lo, const Vec3& hi) : lo_(lo) {
    const Vec3 size = hi - lo;
    const double longest = std::max({size.x, size.y, size.z});
    const double edge = longest > 0 ? longest / kMaxCells : 1.0;
    inv_edge_ = 1 / edge;
    auto count = [&](double s) {
        return std::clamp(static_cast<int>(std::ceil(s / edge)), 1, kMaxCells);
    };
    nx_ = count(size.x);
    ny_ = count(size.y);
    nz_ = count(size.z);
    const std::size_t n = static_cast<std::size_t>(cells());
    sum_.assign(n, 0.0);
    sum2_.assign(n, 0.0);
    mean_.assign(n, -1.0);
    rms_.assign(n, -1.0);
    count_.assign(n, 0);
}

int RadianceGrid::cell(const Vec3& p) const {
    const double fx = (p.x - lo_.x) * inv_edge_, fy = (p.y - lo_.y) * inv_edge_,
                 fz = (p.z - lo_.z) * inv_edge_;
    if (!(fx >= 0 && fy >= 0 && fz >= 0)) return -1;
    const int ix = static_cast<int>(fx), iy = static_cast<int>(fy), iz = static_cast<int>(fz);
    if (ix >= nx_ || iy >= ny_ || iz >= nz_) return -1;
    return (iz * ny_ + iy) * nx_ + ix;
}

int RadianceGrid::learnt_cells() const {
    return static_cast<int>(
        std::count_if(rms_.begin(), rms_.end(), [](double m) { return m >= 0; }));
}

RadianceGrid::Tally::Tally(const RadianceGrid& grid)
    : g(&grid),
      sum(static_cast<std::size_t>(grid.cells()), 0.0),
      sum2(static_cast<std::size_t>(grid.cells()), 0.0),
      count(static_cast<std::size_t>(grid.cells()), 0) {}

void RadianceGrid::Tally::record(const Vec3& p, double value) {
    const int c = g->cell(p);
    if (c < 0 || !(value >= 0) || !std::isfinite(value)) return;
    const std::size_t i = static_cast<std::size_t>(c);
    sum[i] += value;
    sum2[i] += value * value;
    ++count[i];
}

void RadianceGrid::learn(const Tally& t) {
    for (std::size_t c = 0; c < static_cast<std::size_t>(cells()); ++c) {
        sum_[c] += t.sum[c];
        sum2_[c] += t.sum2[c];
        count_[c] += t.count[c];
        const bool enough = count_[c] >= kMinRecords;
        const double n = static_cast<double>(count_[c]);
        mean_[c] = enough ? sum_[c] / n : -1.0;
        rms_[c] = enough ? std::sqrt(sum2_[c] / n) : -1.0;
    }
}

}  // namespace ssslab::volpath
