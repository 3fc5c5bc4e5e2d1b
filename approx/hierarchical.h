// Hierarchical integration of a radial diffusion profile over a point cloud on the media's
// surfaces [JB02] as BSSRDF Explorer renders it [Bitterli13 §2.6.4, §3.3]: the radiant exitance
//
//     M_o(x) = sum over points p of R_d(|x - p|) E(p) A(p)          [Bitterli13 Eq. 2.14, 2.16]
//
// (E(p) the irradiance that entered at p, A(p) the point's share of the surface), with far groups
// of points taken as one: an octree over the points whose nodes hold their total area A_v, total
// power Phi_v = sum E(p) A(p) (RGB) and power-weighted position P_v; a node is opened while its
// solid angle seen from x,
//
//     dw = A_v / |x - P_v|^2                                          [Bitterli13 Eq. 2.40]
//
// exceeds the threshold (the thesis's text says "smaller"; its §3.3.3 and [JB02] open a node while
// the error is too big, as here), and otherwise counts as one point R_d(|x - P_v|) Phi_v. The
// conservative variant [Bitterli13 §2.6.4, end] measures the distance to the node's bounding box
// instead of to P_v (never overestimating it; 0 inside the box, which opens the node). A threshold
// of 0 opens every node: the brute-force sum over all points.
//
// What the result means: M_o is the exitance per unit power entering, summed; the outgoing
// radiance is L_o = F_t(x, w_o) M_o / (pi 4 C_phi(1/eta)) for the dipole family's normalisation
// [Bitterli13 Eq. 2.16], or M_o times the real-time renderer's exit weight (its composite) -- the
// caller's choice, so that every approximation is scored with one exit rule.
//
// Points: Poisson-disk on the triangles by sample elimination [Yuksel15: C. Yuksel, Sample
// elimination for generating Poisson disk sample sets, Eurographics 2015]: candidates_per_point x N
// uniform points (by area, Philox streams keyed by (seed, rng_domain::kPointCloud)), then the most
// crowded candidate removed until N = round(density x area) remain, crowding the weight sum
// (1 - d / 2 r_max)^8 over neighbours closer than 2 r_max, r_max = sqrt(A / (2 sqrt(3) N)) (the
// radius of the densest packing of N disks). Each point then carries the same area A / N: the
// uniform weights the thesis asks for (non-uniform areas show as low-frequency noise [Bitterli13
// §2.6.4]). Bitterli13 spreads points by repulsion [Turk92]; elimination gives the same blue-noise
// distribution without an iteration count to choose.
//
// Lengths in mm throughout (the point cloud is built from scene units with unit_mm).
#pragma once

#include "approx/radial_function.h"
#include "core/mesh.h"
#include "core/vec3.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace ssslab::approx {

/// One point of the cloud.
struct SurfacePoint {
    Vec3 position_mm;
    Vec3 normal;              ///< the facet normal of its triangle (outward for a closed mesh)
    std::uint32_t shape = 0;  ///< caller's shape index
    std::uint32_t triangle = 0;
    double area_mm2 = 0;                 ///< A(p)
    std::array<double, 3> irradiance{};  ///< E(p), power entering per unit area [1/mm^2 units]
};

struct PointCloudOptions {
    double points_per_mm2 = 4;     ///< density; N = max(1, round(density x area))
    int candidates_per_point = 5;  ///< [Yuksel15] uses 5; >= 1 (1: uniform random points)
    std::uint64_t seed = 1;
};

/// Poisson-disk points on `mesh` (positions in scene units, unit_mm mm per unit), every point of
/// area mesh.area() unit_mm^2 / N, tagged with `shape`. Bit-identical for any thread count.
/// Throws std::invalid_argument for a non-positive density or unit, candidates < 1, an empty mesh
/// or one of zero area, or more than 2^26 points.
std::vector<SurfacePoint> sample_surface(const TriangleMesh& mesh, double unit_mm,
                                         std::uint32_t shape, const PointCloudOptions& o);

struct HierarchicalOptions {
    /// The solid-angle threshold epsilon [sr] of Eq. 2.40; 0 sums every point. >= 0.
    double max_solid_angle = 0.05;
    /// Distance to the node's bounding box instead of to its centre of power.
    bool conservative = false;
};

/// What one evaluation did (summed over queries where several are evaluated).
struct HierarchicalStats {
    std::uint64_t nodes_visited = 0;  ///< nodes whose criterion was evaluated
    std::uint64_t clusters = 0;       ///< nodes taken as one point
    std::uint64_t points = 0;         ///< single points summed (in opened leaves)

    HierarchicalStats& operator+=(const HierarchicalStats& o) {
        nodes_visited += o.nodes_visited;
        clusters += o.clusters;
        points += o.points;
        return *this;
    }
};

/// The octree over a point cloud [Bitterli13 §3.3.1]: each node splits its points into the octants
/// about the centre of their bounding box, down to leaf_size points (or max_depth, or points that
/// coincide).
class PointOctree {
  public:
    /// Throws std::invalid_argument for no points, a point with a non-finite position, negative
    /// area or irradiance, leaf_size < 1 or max_depth outside 1..64.
    explicit PointOctree(std::vector<SurfacePoint> points, int leaf_size = 8, int max_depth = 32);

    /// M_o(x) per channel [units of E].
    std::array<double, 3> exitance(const RadialFunction& rd, const Vec3& x_mm,
                                   const HierarchicalOptions& o,
                                   HierarchicalStats* stats = nullptr) const;
    /// Many queries in parallel (oneTBB), one result per query, bit-identical for any thread count.
    std::vector<std::array<double, 3>> exitance(const RadialFunction& rd,
                                                const std::vector<Vec3>& x_mm,
                                                const HierarchicalOptions& o,
                                                HierarchicalStats* stats = nullptr) const;
    /// The sum over every point in order, without the tree: the reference a threshold of 0 must
    /// equal.
    std::array<double, 3> brute_force(const RadialFunction& rd, const Vec3& x_mm) const;

    const std::vector<SurfacePoint>& points() const { return points_; }  ///< in tree order
    std::size_t nodes() const { return nodes_.size(); }
    int depth() const { return depth_; }

  private:
    struct Node {
        Vec3 lo, hi;      ///< bounding box of its points
        Vec3 centre;      ///< P_v: power-weighted (luminance) position; by area if dark
        double area = 0;  ///< A_v
        std::array<double, 3> power{};       ///< Phi_v = sum E A
        std::uint32_t first = 0, count = 0;  ///< its points [first, first + count) in tree order
        std::uint32_t child = 0;             ///< first child (children contiguous); 0: a leaf
        std::uint8_t children = 0;
    };
    void fill(std::uint32_t index, std::uint32_t first, std::uint32_t count, int depth);
    /// m += R_d(|x - p|) E(p) A(p); nothing for a dark point (R_d may be infinite at 0).
    static void add_point(const RadialFunction& rd, const Vec3& x, const Vec3& p,
                          const std::array<double, 3>& power, std::array<double, 3>& m);
    void visit(const Node& n, const RadialFunction& rd, const Vec3& x, const HierarchicalOptions& o,
               std::array<double, 3>& m, HierarchicalStats& s) const;

    std::vector<SurfacePoint> points_;
    std::vector<Node> nodes_;
    int leaf_size_ = 8, max_depth_ = 32, depth_ = 0;
};

/// A Jensen-Buhler variant as experiment configs name it (experiments/runner renders it into a
/// frame): "density=4,threshold=0.05", "threshold=0.01,bound=box", "profile=dipole".
struct JensenBuhlerOptions {
    double points_per_mm2 = 4;      ///< density: > 0, at most 1e4
    double max_solid_angle = 0.05;  ///< threshold [sr]: >= 0 (0: the brute-force sum), finite
    bool conservative = false;      ///< bound = centre (false) | box (the conservative variant)
    /// The radial profile integrated: "mc" (the material's MC profile, the one the separable
    /// models are built from) or an analytic model of approx/diffusion.h by its factory name
    /// (dipole, better-dipole, pbd, ...) for the material's coefficients.
    std::string profile = "mc";
    int candidates_per_point = 5;  ///< candidates: 1..64 (PointCloudOptions)
};

/// Parse a variant (keys density, threshold, bound = centre | box, profile, candidates; unset
/// keys keep JensenBuhlerOptions' defaults). Throws std::invalid_argument naming the key: not
/// key=value, a key twice, an unknown key or value, a threshold below 0, a density not above 0.
JensenBuhlerOptions parse_jensen_buhler(const std::string& text);
/// The canonical text of a variant (every key), e.g. for listing each variant once.
std::string jensen_buhler_label(const JensenBuhlerOptions& o);

}  // namespace ssslab::approx
