#include "approx/hierarchical.h"

#include "approx/diffusion.h"
#include "approx/option_list.h"

#include "core/rng.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <sstream>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace ssslab::approx {

// ---- Point cloud --------------------------------------------------------------------------------

namespace {

/// Candidates bucketed by a uniform grid of cell `cell` over their bounds, for neighbour queries
/// within one cell size.
class CellGrid {
  public:
    CellGrid(const std::vector<Vec3>& p, double cell) : p_(p) {
        lo_ = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
               std::numeric_limits<double>::infinity()};
        Vec3 hi = -lo_;
        for (const Vec3& q : p) {
            lo_ = {std::min(lo_.x, q.x), std::min(lo_.y, q.y), std::min(lo_.z, q.z)};
            hi = {std::max(hi.x, q.x), std::max(hi.y, q.y), std::max(hi.z, q.z)};
        }
        // 21 bits per axis in the key: a grid too fine for that gets coarser cells (more
        // candidates per query, the same result).
        const double extent = std::max({hi.x - lo_.x, hi.y - lo_.y, hi.z - lo_.z});
        cell_ = std::max(cell, extent / double(1 << 20));
        for (std::uint32_t i = 0; i < p.size(); ++i) cells_[key(coords(p[i]))].push_back(i);
    }
    /// Calls f(j) for every candidate j != i within `radius` (<= the cell size) of candidate i,
    /// in a fixed order.
    template <class F>
    void near(std::uint32_t i, double radius, F&& f) const {
        const auto c = coords(p_[i]);
        const double r2 = radius * radius;
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const std::array<std::int64_t, 3> n = {c[0] + dx, c[1] + dy, c[2] + dz};
                    if (n[0] < 0 || n[1] < 0 || n[2] < 0) continue;
                    const auto it = cells_.find(key(n));
                    if (it == cells_.end()) continue;
                    for (std::uint32_t j : it->second) {
                        if (j == i) continue;
                        const Vec3 d = p_[j] - p_[i];
                        const double d2 = dot(d, d);
                        if (d2 < r2) f(j, std::sqrt(d2));
                    }
                }
    }

  private:
    std::array<std::int64_t, 3> coords(const Vec3& q) const {
        return {static_cast<std::int64_t>((q.x - lo_.x) / cell_),
                static_cast<std::int64_t>((q.y - lo_.y) / cell_),
                static_cast<std::int64_t>((q.z - lo_.z) / cell_)};
    }
    static std::uint64_t key(const std::array<std::int64_t, 3>& c) {
        return static_cast<std::uint64_t>(c[0]) | static_cast<std::uint64_t>(c[1]) << 21 |
               static_cast<std::uint64_t>(c[2]) << 42;
    }
    const std::vector<Vec3>& p_;
    Vec3 lo_;
    double cell_ = 1;
    std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> cells_;
};

}  // namespace

std::vector<SurfacePoint> sample_surface(const TriangleMesh& mesh, double unit_mm,
                                         std::uint32_t shape, const PointCloudOptions& o) {
    if (!(o.points_per_mm2 > 0) || !std::isfinite(o.points_per_mm2))
        throw std::invalid_argument("sample_surface: points_per_mm2 must be > 0");
    if (!(unit_mm > 0) || !std::isfinite(unit_mm))
        throw std::invalid_argument("sample_surface: unit_mm must be > 0");
    if (o.candidates_per_point < 1)
        throw std::invalid_argument("sample_surface: candidates_per_point must be >= 1");
    // Triangle areas [mm^2] and their cumulative sums, for sampling by area.
    std::vector<double> cdf(mesh.triangles.size() + 1, 0.0);
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        const auto& tri = mesh.triangles[t];
        const Vec3 &a = mesh.positions[tri[0]], &b = mesh.positions[tri[1]],
                   &c = mesh.positions[tri[2]];
        cdf[t + 1] = cdf[t] + 0.5 * length(cross(b - a, c - a)) * unit_mm * unit_mm;
    }
    const double area = cdf.back();
    if (mesh.triangles.empty() || !(area > 0) || !std::isfinite(area))
        throw std::invalid_argument("sample_surface: the mesh has no area");
    const double wanted = std::max(1.0, std::round(o.points_per_mm2 * area));
    if (wanted * o.candidates_per_point > double(1 << 26))
        throw std::invalid_argument("sample_surface: " + std::to_string(wanted) +
                                    " points x candidates is more than 2^26");
    const size_t n = static_cast<size_t>(wanted);
    const size_t m = n * static_cast<size_t>(o.candidates_per_point);

    // Candidates: uniform by area, one Philox stream each.
    std::vector<Vec3> pos(m);
    std::vector<std::uint32_t> tri_of(m);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, m, 4096), [&](const auto& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
            RngStream rng(o.seed, rng_domain::kPointCloud, i);
            const double u = rng.uniform() * area;
            size_t t =
                static_cast<size_t>(std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin()) - 1;
            t = std::min(t, mesh.triangles.size() - 1);
            while (t > 0 && !(cdf[t + 1] > cdf[t])) --t;  // never a triangle of zero area
            const double s = std::sqrt(rng.uniform()), v = rng.uniform();
            const auto& tri = mesh.triangles[t];
            const Vec3 &a = mesh.positions[tri[0]], &b = mesh.positions[tri[1]],
                       &c = mesh.positions[tri[2]];
            pos[i] = (a * (1 - s) + b * (s * (1 - v)) + c * (s * v)) * unit_mm;
            tri_of[i] = static_cast<std::uint32_t>(t);
        }
    });

    std::vector<char> keep(m, 1);
    if (m > n) {
        // Sample elimination [Yuksel15 §3]: weights of the neighbours within 2 r_max.
        const double r_max = std::sqrt(area / (2 * std::sqrt(3.0) * static_cast<double>(n)));
        const double reach = 2 * r_max;
        const CellGrid grid(pos, reach);
        std::vector<double> weight(m, 0.0);
        auto w = [reach](double d) { return std::pow(1 - d / reach, 8); };
        tbb::parallel_for(tbb::blocked_range<size_t>(0, m, 1024), [&](const auto& r) {
            for (size_t i = r.begin(); i < r.end(); ++i)
                grid.near(static_cast<std::uint32_t>(i), reach,
                          [&](std::uint32_t, double d) { weight[i] += w(d); });
        });
        // The most crowded first (ties: the higher index), stale heap entries skipped.
        std::priority_queue<std::pair<double, std::uint32_t>> heap;
        for (std::uint32_t i = 0; i < m; ++i) heap.push({weight[i], i});
        size_t left = m;
        while (left > n) {
            const auto [wi, i] = heap.top();
            heap.pop();
            if (!keep[i] || wi != weight[i]) continue;
            keep[i] = 0;
            --left;
            grid.near(i, reach, [&](std::uint32_t j, double d) {
                if (!keep[j]) return;
                weight[j] -= w(d);
                heap.push({weight[j], j});
            });
        }
    }
    std::vector<SurfacePoint> out;
    out.reserve(n);
    const double each = area / static_cast<double>(n);
    for (size_t i = 0; i < m; ++i) {
        if (!keep[i]) continue;
        SurfacePoint p;
        p.position_mm = pos[i];
        p.normal = mesh.facet_normal(tri_of[i]);
        p.shape = shape;
        p.triangle = tri_of[i];
        p.area_mm2 = each;
        out.push_back(p);
    }
    return out;
}

namespace {

std::array<double, 3> point_power(const SurfacePoint& p) {
    return {p.irradiance[0] * p.area_mm2, p.irradiance[1] * p.area_mm2,
            p.irradiance[2] * p.area_mm2};
}

double box_distance2(const Vec3& x, const Vec3& lo, const Vec3& hi) {
    const double dx = std::max({lo.x - x.x, 0.0, x.x - hi.x});
    const double dy = std::max({lo.y - x.y, 0.0, x.y - hi.y});
    const double dz = std::max({lo.z - x.z, 0.0, x.z - hi.z});
    return dx * dx + dy * dy + dz * dz;
}

}  // namespace

// ---- Octree -------------------------------------------------------------------------------------

PointOctree::PointOctree(std::vector<SurfacePoint> points, int leaf_size, int max_depth)
    : points_(std::move(points)), leaf_size_(leaf_size), max_depth_(max_depth) {
    if (points_.empty()) throw std::invalid_argument("PointOctree: no points");
    if (points_.size() >= (size_t(1) << 32))
        throw std::invalid_argument("PointOctree: more than 2^32 points");
    if (leaf_size < 1) throw std::invalid_argument("PointOctree: leaf_size must be >= 1");
    if (max_depth < 1 || max_depth > 64)
        throw std::invalid_argument("PointOctree: max_depth must be in 1..64");
    for (size_t i = 0; i < points_.size(); ++i) {
        const SurfacePoint& p = points_[i];
        bool ok = all_finite(p.position_mm) && std::isfinite(p.area_mm2) && p.area_mm2 >= 0;
        for (double e : p.irradiance) ok = ok && std::isfinite(e) && e >= 0;
        if (!ok)
            throw std::invalid_argument("PointOctree: point " + std::to_string(i) +
                                        " has a non-finite position or a negative or non-finite "
                                        "area or irradiance");
    }
    nodes_.reserve(2 * points_.size() / static_cast<size_t>(leaf_size) + 1);
    nodes_.emplace_back();
    fill(0, 0, static_cast<std::uint32_t>(points_.size()), 1);
}

void PointOctree::fill(std::uint32_t index, std::uint32_t first, std::uint32_t count, int depth) {
    depth_ = std::max(depth_, depth);
    Node n;
    n.first = first;
    n.count = count;
    const double inf = std::numeric_limits<double>::infinity();
    n.lo = {inf, inf, inf};
    n.hi = -n.lo;
    Vec3 by_power, by_area;
    double power_sum = 0;
    for (std::uint32_t i = first; i < first + count; ++i) {
        const SurfacePoint& p = points_[i];
        const Vec3& q = p.position_mm;
        n.lo = {std::min(n.lo.x, q.x), std::min(n.lo.y, q.y), std::min(n.lo.z, q.z)};
        n.hi = {std::max(n.hi.x, q.x), std::max(n.hi.y, q.y), std::max(n.hi.z, q.z)};
        n.area += p.area_mm2;
        const std::array<double, 3> pp = point_power(p);
        double pw = 0;
        for (int c = 0; c < 3; ++c) {
            n.power[c] += pp[c];
            pw += pp[c];
        }
        by_power += q * pw;
        power_sum += pw;
        by_area += q * p.area_mm2;
    }
    // P_v: the centre of power (channels summed); of area where the node is dark; the box's
    // centre where it has no area either.
    if (power_sum > 0)
        n.centre = by_power * (1 / power_sum);
    else if (n.area > 0)
        n.centre = by_area * (1 / n.area);
    else
        n.centre = (n.lo + n.hi) * 0.5;
    // Keep the centre inside the box (rounding of the weighted mean).
    n.centre = {std::clamp(n.centre.x, n.lo.x, n.hi.x), std::clamp(n.centre.y, n.lo.y, n.hi.y),
                std::clamp(n.centre.z, n.lo.z, n.hi.z)};

    const bool split =
        count > static_cast<std::uint32_t>(leaf_size_) && depth < max_depth_ && !(n.lo == n.hi);
    if (!split) {
        nodes_[index] = n;
        return;
    }
    // Octants about the box's centre (a point on the centre plane goes below it): with the box
    // not a point, its extreme points differ in some axis, so at least two octants are filled.
    const Vec3 mid = (n.lo + n.hi) * 0.5;
    auto octant = [&mid](const Vec3& q) {
        return (q.x > mid.x ? 1 : 0) | (q.y > mid.y ? 2 : 0) | (q.z > mid.z ? 4 : 0);
    };
    std::array<std::uint32_t, 9> start{};
    for (std::uint32_t i = first; i < first + count; ++i)
        ++start[octant(points_[i].position_mm) + 1];
    for (int k = 0; k < 8; ++k) start[k + 1] += start[k];
    std::vector<SurfacePoint> sorted(count);
    std::array<std::uint32_t, 8> at{};
    std::copy(start.begin(), start.begin() + 8, at.begin());
    for (std::uint32_t i = first; i < first + count; ++i)
        sorted[at[octant(points_[i].position_mm)]++] = points_[i];
    std::copy(sorted.begin(), sorted.end(), points_.begin() + first);
    int filled = 0;
    for (int k = 0; k < 8; ++k) filled += start[k + 1] > start[k];
    n.child = static_cast<std::uint32_t>(nodes_.size());
    n.children = static_cast<std::uint8_t>(filled);
    nodes_[index] = n;
    nodes_.resize(nodes_.size() + static_cast<size_t>(filled));
    std::uint32_t c = n.child;
    for (int k = 0; k < 8; ++k)
        if (start[k + 1] > start[k])
            fill(c++, first + start[k], start[k + 1] - start[k], depth + 1);
}

void PointOctree::add_point(const RadialFunction& rd, const Vec3& x, const Vec3& p,
                            const std::array<double, 3>& power, std::array<double, 3>& m) {
    if (power[0] == 0 && power[1] == 0 && power[2] == 0) return;
    const std::array<double, 3> f = rd(length(x - p));
    for (int c = 0; c < 3; ++c)
        if (power[c] != 0) m[c] += f[c] * power[c];
}

void PointOctree::visit(const Node& n, const RadialFunction& rd, const Vec3& x,
                        const HierarchicalOptions& o, std::array<double, 3>& m,
                        HierarchicalStats& s) const {
    ++s.nodes_visited;
    // [Bitterli13 Eq. 2.40]: a node far enough for its solid angle is one point at P_v.
    const Vec3 to_centre = x - n.centre;
    const double d2 = o.conservative ? box_distance2(x, n.lo, n.hi) : dot(to_centre, to_centre);
    if (n.area <= o.max_solid_angle * d2) {
        add_point(rd, x, n.centre, n.power, m);
        ++s.clusters;
        return;
    }
    if (n.child == 0) {
        for (std::uint32_t i = n.first; i < n.first + n.count; ++i) {
            const SurfacePoint& p = points_[i];
            add_point(rd, x, p.position_mm, point_power(p), m);
        }
        s.points += n.count;
        return;
    }
    for (std::uint32_t k = 0; k < n.children; ++k) visit(nodes_[n.child + k], rd, x, o, m, s);
}

std::array<double, 3> PointOctree::exitance(const RadialFunction& rd, const Vec3& x_mm,
                                            const HierarchicalOptions& o,
                                            HierarchicalStats* stats) const {
    if (!(o.max_solid_angle >= 0))
        throw std::invalid_argument("PointOctree: max_solid_angle must be >= 0");
    std::array<double, 3> m{};
    HierarchicalStats s;
    visit(nodes_[0], rd, x_mm, o, m, s);
    if (stats) *stats += s;
    return m;
}

std::vector<std::array<double, 3>> PointOctree::exitance(const RadialFunction& rd,
                                                         const std::vector<Vec3>& x_mm,
                                                         const HierarchicalOptions& o,
                                                         HierarchicalStats* stats) const {
    if (!(o.max_solid_angle >= 0))  // also with no queries
        throw std::invalid_argument("PointOctree: max_solid_angle must be >= 0");
    std::vector<std::array<double, 3>> out(x_mm.size());
    tbb::combinable<HierarchicalStats> counts;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, x_mm.size(), 64), [&](const auto& r) {
        for (size_t i = r.begin(); i < r.end(); ++i)
            out[i] = exitance(rd, x_mm[i], o, &counts.local());
    });
    if (stats) counts.combine_each([stats](const HierarchicalStats& s) { *stats += s; });
    return out;
}

std::array<double, 3> PointOctree::brute_force(const RadialFunction& rd, const Vec3& x_mm) const {
    std::array<double, 3> m{};
    for (const SurfacePoint& p : points_) add_point(rd, x_mm, p.position_mm, point_power(p), m);
    return m;
}

JensenBuhlerOptions parse_jensen_buhler(const std::string& text) {
    JensenBuhlerOptions o;
    const OptionList list("jensen_buhler", text);
    for (const auto& [key, v] : list.items()) {
        if (key == "density") {
            o.points_per_mm2 = list.number(key, v);
            if (!(o.points_per_mm2 > 0 && o.points_per_mm2 <= 1e4))
                list.fail("density must be in (0, 1e4] points per mm^2, got " + v);
        } else if (key == "threshold") {
            o.max_solid_angle = list.number(key, v);
            if (!(o.max_solid_angle >= 0))
                list.fail("threshold must be >= 0 sr (0: every point), got " + v);
        } else if (key == "bound" && (v == "centre" || v == "box")) {
            o.conservative = v == "box";
        } else if (key == "profile") {
            const auto& names = diffusion_model_names();
            if (v != "mc" && std::find(names.begin(), names.end(), v) == names.end()) {
                std::string known = "mc";
                for (const std::string& n : names) known += ", " + n;
                list.fail("profile \"" + v + "\" is unknown (known: " + known + ")");
            }
            o.profile = v;
        } else if (key == "candidates") {
            o.candidates_per_point = list.whole(key, v);
            if (o.candidates_per_point < 1 || o.candidates_per_point > 64)
                list.fail("candidates must be in 1..64, got " + v);
        } else if (key == "bound") {
            list.fail("bound \"" + v + "\" is unknown (known: centre, box)");
        } else {
            list.fail("unknown key \"" + key +
                      "\" (known: density, threshold, bound, profile, candidates)");
        }
    }
    return o;
}

std::string jensen_buhler_label(const JensenBuhlerOptions& o) {
    std::ostringstream s;
    s << "density=" << o.points_per_mm2 << ",threshold=" << o.max_solid_angle
      << ",bound=" << (o.conservative ? "box" : "centre") << ",profile=" << o.profile
      << ",candidates=" << o.candidates_per_point;
    return s.str();
}

}  // namespace ssslab::approx
