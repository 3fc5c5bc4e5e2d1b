// Triangle meshes shared by the path tracer (through Embree) and the real-time renderers:
// procedural shapes tessellated from their parameters, Wavefront OBJ files read through
// tinyobjloader, transforms, and the checks a mesh bound to a medium must pass (finite vertices,
// closed and consistently oriented: every edge shared by exactly two triangles that traverse it
// in opposite directions).
#pragma once

#include "core/vec3.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace ssslab {

struct TriangleMesh {
    std::vector<Vec3> positions;
    /// Vertex indices, counter-clockwise seen from outside (the geometric normal
    /// (p1 - p0) x (p2 - p0) points out of a closed mesh).
    std::vector<std::array<std::uint32_t, 3>> triangles;

    /// The unit geometric normal of triangle t, normalize((p1 - p0) x (p2 - p0)): outward for a
    /// closed mesh. The facet normal of every engine (volpath's hits and "normal" layer, the
    /// real-time G-buffer on either backend), written once so that they agree to the bit.
    Vec3 facet_normal(std::size_t t) const {
        const auto& tri = triangles[t];
        const Vec3 &v0 = positions[tri[0]], &v1 = positions[tri[1]], &v2 = positions[tri[2]];
        return normalize(cross(v1 - v0, v2 - v0));
    }
    double area() const;
    /// Signed enclosed volume (divergence theorem): positive for an outward-oriented closed mesh.
    double volume() const;
    /// Axis-aligned bounds (min, max); {inf, -inf} for an empty mesh.
    std::array<Vec3, 2> bounds() const;
    /// Append another mesh (indices shifted).
    void append(const TriangleMesh& other);
};

/// Scale (per axis), then rotate (about x, then y, then z, in degrees), then translate.
struct Transform {
    Vec3 scale{1, 1, 1};
    Vec3 rotate_deg{0, 0, 0};
    Vec3 translate{0, 0, 0};

    Vec3 apply(const Vec3& p) const;
    /// Mirroring scales (an odd number of negative factors) flip the triangles' winding back.
    bool mirrors() const { return scale.x * scale.y * scale.z < 0; }
};
TriangleMesh transformed(const TriangleMesh& m, const Transform& t);

// Procedural shapes, closed and outward-oriented (the quad excepted), centred at the origin.
/// Icosphere: the icosahedron subdivided `subdivisions` times (20 x 4^s triangles), projected.
TriangleMesh make_sphere(double radius, int subdivisions);
/// Axis-aligned box of the given edge lengths.
TriangleMesh make_box(const Vec3& size);
/// Torus around the z axis: ring radius `major`, tube radius `minor` (< major).
TriangleMesh make_torus(double major, double minor, int segments_major, int segments_minor);
/// A rectangle in the x-z plane facing +y (one-sided, open): for floors and occluders.
TriangleMesh make_quad(double size_x, double size_z);
/// A sphere with surface detail: the icosphere's radius modulated by 1 + amplitude * f(n), f a
/// sum of 8 random plane waves of spatial frequency `frequency` (cycles per radian) with
/// amplitudes falling as 1/k, normalised to max |f| <= 1; deterministic for a seed.
TriangleMesh make_bumpy_sphere(double radius, double amplitude, double frequency,
                               std::uint64_t seed, int subdivisions);

/// Topology of a mesh bound to a medium.
struct MeshCheck {
    std::size_t boundary_edges = 0;        ///< edges used by one triangle
    std::size_t nonmanifold_edges = 0;     ///< edges used by more than two triangles
    std::size_t inconsistent_edges = 0;    ///< edges traversed twice in the same direction
    std::size_t degenerate_triangles = 0;  ///< zero area or repeated vertex
    std::size_t nonfinite_vertices = 0;
    std::size_t first_nonfinite_vertex = 0;  ///< index, when nonfinite_vertices > 0
    bool closed() const {
        return boundary_edges == 0 && nonmanifold_edges == 0 && inconsistent_edges == 0;
    }
    /// "closed", or what is wrong ("12 boundary edges, 3 edges used by more than two
    /// triangles, ...").
    std::string describe() const;
};
MeshCheck check_mesh(const TriangleMesh& m);

/// Whether the segment a-b crosses triangle t of m (Moller-Trumbore, endpoints included).
bool segment_hits_triangle(const TriangleMesh& m, std::size_t t, const Vec3& a, const Vec3& b);
/// Whether p lies inside the closed mesh m (parity of the crossings of a ray in a fixed
/// direction; O(triangles)).
bool inside_mesh(const TriangleMesh& m, const Vec3& p);
/// Whether two meshes intersect or one lies inside the other (closed ones), judged from up to
/// `samples` evenly spread edges and vertices of each: a check that catches shapes placed into
/// each other, not a proof that they are apart.
bool meshes_overlap(const TriangleMesh& a, bool a_closed, const TriangleMesh& b, bool b_closed,
                    std::size_t samples = 256);

/// Read a Wavefront OBJ file (all objects and groups merged; polygons triangulated by
/// tinyobjloader). Throws InputError naming the file and line for a file that cannot be read or
/// parsed, a vertex with a non-finite coordinate, a face index out of range, and a file without
/// triangles.
TriangleMesh load_obj(const std::string& path);
/// Write a mesh as OBJ text (vertices with %.17g, faces 1-based).
std::string to_obj(const TriangleMesh& m);

}  // namespace ssslab
