#include "core/mesh.h"

#include "core/error.h"
#include "core/rng.h"

#include <tiny_obj_loader.h>

#include <algorithm>
#include <cctype>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <sstream>
#include <unordered_map>

namespace ssslab {

namespace {

constexpr double kPi = std::numbers::pi;

using Tri = std::array<std::uint32_t, 3>;

std::uint32_t u32(std::size_t i) {
    return static_cast<std::uint32_t>(i);
}

// The icosphere on the unit sphere: positions are unit vectors.
TriangleMesh unit_icosphere(int subdivisions) {
    if (subdivisions < 0 || subdivisions > 9)
        throw std::invalid_argument("sphere subdivisions must lie in [0, 9]");
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    TriangleMesh m;
    m.positions = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                   {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
    for (Vec3& p : m.positions) p = normalize(p);
    m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                   {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                   {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                   {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    for (int s = 0; s < subdivisions; ++s) {
        std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
        auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
            const auto key = std::minmax(a, b);
            auto it = mid.find(key);
            if (it != mid.end()) return it->second;
            m.positions.push_back(normalize((m.positions[a] + m.positions[b]) * 0.5));
            const std::uint32_t i = u32(m.positions.size() - 1);
            mid.emplace(key, i);
            return i;
        };
        std::vector<Tri> next;
        next.reserve(m.triangles.size() * 4);
        for (const Tri& tr : m.triangles) {
            const std::uint32_t a = midpoint(tr[0], tr[1]), b = midpoint(tr[1], tr[2]),
                                c = midpoint(tr[2], tr[0]);
            next.push_back({tr[0], a, c});
            next.push_back({tr[1], b, a});
            next.push_back({tr[2], c, b});
            next.push_back({a, b, c});
        }
        m.triangles = std::move(next);
    }
    return m;
}

Vec3 rotate_xyz(const Vec3& p, const Vec3& deg) {
    const double ax = deg.x * kPi / 180, ay = deg.y * kPi / 180, az = deg.z * kPi / 180;
    Vec3 q = p;
    if (ax != 0)
        q = {q.x, std::cos(ax) * q.y - std::sin(ax) * q.z, std::sin(ax) * q.y + std::cos(ax) * q.z};
    if (ay != 0)
        q = {std::cos(ay) * q.x + std::sin(ay) * q.z, q.y,
             -std::sin(ay) * q.x + std::cos(ay) * q.z};
    if (az != 0)
        q = {std::cos(az) * q.x - std::sin(az) * q.y, std::sin(az) * q.x + std::cos(az) * q.y, q.z};
    return q;
}

// "line 12" or "line: 12" in a tinyobjloader message; 0 if none.
int line_in(const std::string& msg) {
    for (std::size_t i = msg.find("line"); i != std::string::npos; i = msg.find("line", i + 4)) {
        std::size_t j = i + 4;
        if (j < msg.size() && msg[j] == ':') ++j;
        if (j < msg.size() && msg[j] == ' ') ++j;
        if (j < msg.size() && std::isdigit(static_cast<unsigned char>(msg[j])))
            return std::atoi(msg.c_str() + j);
    }
    return 0;
}

std::string first_line(const std::string& s) {
    std::string out = s.substr(0, s.find('\n'));
    while (!out.empty() && (out.back() == '\r' || out.back() == ' ')) out.pop_back();
    return out;
}

}  // namespace

double TriangleMesh::area() const {
    double a = 0;
    for (const Tri& t : triangles)
        a += 0.5 *
             length(cross(positions[t[1]] - positions[t[0]], positions[t[2]] - positions[t[0]]));
    return a;
}

double TriangleMesh::volume() const {
    double v = 0;
    for (const Tri& t : triangles)
        v += dot(positions[t[0]], cross(positions[t[1]], positions[t[2]])) / 6.0;
    return v;
}

std::array<Vec3, 2> TriangleMesh::bounds() const {
    const double inf = std::numeric_limits<double>::infinity();
    Vec3 lo{inf, inf, inf}, hi{-inf, -inf, -inf};
    for (const Vec3& p : positions) {
        lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
        hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
    }
    return {lo, hi};
}

void TriangleMesh::append(const TriangleMesh& other) {
    const std::uint32_t base = u32(positions.size());
    positions.insert(positions.end(), other.positions.begin(), other.positions.end());
    for (const Tri& t : other.triangles)
        triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
}

Vec3 Transform::apply(const Vec3& p) const {
    return rotate_xyz({p.x * scale.x, p.y * scale.y, p.z * scale.z}, rotate_deg) + translate;
}

TriangleMesh transformed(const TriangleMesh& m, const Transform& t) {
    TriangleMesh out;
    out.positions.reserve(m.positions.size());
    for (const Vec3& p : m.positions) out.positions.push_back(t.apply(p));
    out.triangles = m.triangles;
    if (t.mirrors())
        for (Tri& tr : out.triangles) std::swap(tr[1], tr[2]);
    return out;
}

TriangleMesh make_sphere(double radius, int subdivisions) {
    TriangleMesh m = unit_icosphere(subdivisions);
    for (Vec3& p : m.positions) p = p * radius;
    return m;
}

TriangleMesh make_box(const Vec3& size) {
    const double x = 0.5 * size.x, y = 0.5 * size.y, z = 0.5 * size.z;
    TriangleMesh m;
    m.positions = {{-x, -y, -z}, {x, -y, -z}, {x, y, -z}, {-x, y, -z},
                   {-x, -y, z},  {x, -y, z},  {x, y, z},  {-x, y, z}};
    // Two triangles per face, counter-clockwise seen from outside.
    m.triangles = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                   {3, 6, 2}, {3, 7, 6}, {0, 4, 7}, {0, 7, 3}, {1, 2, 6}, {1, 6, 5}};
    return m;
}

TriangleMesh make_torus(double major, double minor, int nu, int nv) {
    if (!(minor > 0 && major > minor)) throw std::invalid_argument("torus needs 0 < minor < major");
    if (nu < 3 || nv < 3) throw std::invalid_argument("torus needs at least 3 x 3 segments");
    TriangleMesh m;
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            const double u = 2 * kPi * i / nu, v = 2 * kPi * j / nv;
            const double r = major + minor * std::cos(v);
            m.positions.push_back({r * std::cos(u), r * std::sin(u), minor * std::sin(v)});
        }
    auto idx = [&](int i, int j) {
        return u32(static_cast<std::size_t>((i % nu) * nv + (j % nv)));
    };
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            const std::uint32_t a = idx(i, j), b = idx(i + 1, j), c = idx(i + 1, j + 1),
                                d = idx(i, j + 1);
            m.triangles.push_back({a, b, c});
            m.triangles.push_back({a, c, d});
        }
    return m;
}

TriangleMesh make_quad(double sx, double sz) {
    const double x = 0.5 * sx, z = 0.5 * sz;
    TriangleMesh m;
    m.positions = {{-x, 0, -z}, {x, 0, -z}, {x, 0, z}, {-x, 0, z}};
    m.triangles = {{0, 2, 1}, {0, 3, 2}};  // normal +y
    return m;
}

TriangleMesh make_bumpy_sphere(double radius, double amplitude, double frequency,
                               std::uint64_t seed, int subdivisions) {
    if (!(std::fabs(amplitude) < 1))
        throw std::invalid_argument("bumpy sphere amplitude must lie in (-1, 1)");
    TriangleMesh m = unit_icosphere(subdivisions);
    // 8 plane waves cos(k freq (d_k . n) + phase_k) / k with random unit d_k and phases.
    RngStream rng(seed, rng_domain::kScene, 0);
    struct Wave {
        Vec3 d;
        double phase, k;
    };
    std::vector<Wave> waves;
    double norm = 0;
    for (int k = 1; k <= 8; ++k) {
        const double z = 2 * rng.uniform() - 1, phi = 2 * kPi * rng.uniform();
        const double s = std::sqrt(std::max(0.0, 1 - z * z));
        waves.push_back(
            {{s * std::cos(phi), s * std::sin(phi), z}, 2 * kPi * rng.uniform(), double(k)});
        norm += 1.0 / k;
    }
    for (Vec3& n : m.positions) {
        double f = 0;
        for (const Wave& w : waves) f += std::cos(w.k * frequency * dot(w.d, n) + w.phase) / w.k;
        n = n * (radius * (1 + amplitude * f / norm));
    }
    return m;
}

std::string MeshCheck::describe() const {
    if (closed() && degenerate_triangles == 0 && nonfinite_vertices == 0) return "closed";
    std::string s;
    auto add = [&](std::size_t n, const char* what) {
        if (n == 0) return;
        s += (s.empty() ? "" : ", ") + std::to_string(n) + " " + what;
    };
    add(nonfinite_vertices, "non-finite vertices");
    add(boundary_edges, "boundary edges (holes)");
    add(nonmanifold_edges, "edges used by more than two triangles");
    add(inconsistent_edges, "edges traversed twice in the same direction (flipped triangles)");
    add(degenerate_triangles, "degenerate triangles");
    return s;
}

MeshCheck check_mesh(const TriangleMesh& m) {
    MeshCheck c;
    for (std::size_t i = 0; i < m.positions.size(); ++i)
        if (!all_finite(m.positions[i]) && c.nonfinite_vertices++ == 0)
            c.first_nonfinite_vertex = i;
    // Directed edge counts: a closed, consistently oriented mesh has every directed edge once and
    // its reverse once.
    std::unordered_map<std::uint64_t, int> directed;
    directed.reserve(m.triangles.size() * 3);
    auto key = [](std::uint32_t a, std::uint32_t b) { return (std::uint64_t{a} << 32) | b; };
    for (const Tri& t : m.triangles) {
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
            ++c.degenerate_triangles;
            continue;
        }
        const Vec3 n =
            cross(m.positions[t[1]] - m.positions[t[0]], m.positions[t[2]] - m.positions[t[0]]);
        if (!(dot(n, n) > 0)) ++c.degenerate_triangles;
        for (int e = 0; e < 3; ++e)
            ++directed[key(t[static_cast<size_t>(e)], t[static_cast<size_t>((e + 1) % 3)])];
    }
    for (const auto& [k, n] : directed) {
        const std::uint32_t a = static_cast<std::uint32_t>(k >> 32),
                            b = static_cast<std::uint32_t>(k);
        auto it = directed.find(key(b, a));
        const int back = it == directed.end() ? 0 : it->second;
        if (n > 1) ++c.inconsistent_edges;
        if (n + back > 2 && a < b) ++c.nonmanifold_edges;
        if (back == 0) ++c.boundary_edges;
    }
    return c;
}

bool segment_hits_triangle(const TriangleMesh& m, std::size_t t, const Vec3& a, const Vec3& b) {
    const auto& tr = m.triangles[t];
    const Vec3 p0 = m.positions[tr[0]], e1 = m.positions[tr[1]] - p0, e2 = m.positions[tr[2]] - p0;
    const Vec3 d = b - a;
    const Vec3 pv = cross(d, e2);
    const double det = dot(e1, pv);
    if (std::fabs(det) < 1e-300) return false;
    const double inv = 1.0 / det;
    const Vec3 tv = a - p0;
    const double u = dot(tv, pv) * inv;
    if (u < 0 || u > 1) return false;
    const Vec3 qv = cross(tv, e1);
    const double v = dot(d, qv) * inv;
    if (v < 0 || u + v > 1) return false;
    const double s = dot(e2, qv) * inv;
    return s >= 0 && s <= 1;
}

bool inside_mesh(const TriangleMesh& m, const Vec3& p) {
    // A direction unlikely to graze edges of axis-aligned or symmetric meshes.
    const Vec3 d = normalize(Vec3{0.5773502691896258, 0.5360562674188974, 0.6159384228628216});
    const auto b = m.bounds();
    const double reach = 2 * (length(b[1] - b[0]) + length(p - b[0])) + 1;
    const Vec3 far = p + d * reach;
    int n = 0;
    for (std::size_t t = 0; t < m.triangles.size(); ++t) n += segment_hits_triangle(m, t, p, far);
    return n % 2 == 1;
}

bool meshes_overlap(const TriangleMesh& a, bool a_closed, const TriangleMesh& b, bool b_closed,
                    std::size_t samples) {
    const auto ba = a.bounds(), bb = b.bounds();
    for (int k = 0; k < 3; ++k)
        if (ba[1][k] < bb[0][k] || bb[1][k] < ba[0][k]) return false;
    auto edges_cross = [&](const TriangleMesh& x, const TriangleMesh& y) {
        if (x.triangles.empty()) return false;
        const std::size_t n = std::min(samples, x.triangles.size());
        for (std::size_t i = 0; i < n; ++i) {
            const auto& tr = x.triangles[i * x.triangles.size() / n];
            for (int e = 0; e < 3; ++e) {
                const Vec3 p = x.positions[tr[static_cast<size_t>(e)]];
                const Vec3 q = x.positions[tr[static_cast<size_t>((e + 1) % 3)]];
                for (std::size_t t = 0; t < y.triangles.size(); ++t)
                    if (segment_hits_triangle(y, t, p, q)) return true;
            }
        }
        return false;
    };
    auto vertex_inside = [&](const TriangleMesh& x, const TriangleMesh& y) {
        if (x.positions.empty()) return false;
        const std::size_t n = std::min<std::size_t>(8, x.positions.size());
        for (std::size_t i = 0; i < n; ++i)
            if (inside_mesh(y, x.positions[i * x.positions.size() / n])) return true;
        return false;
    };
    if (edges_cross(a, b) || edges_cross(b, a)) return true;
    if (b_closed && vertex_inside(a, b)) return true;
    if (a_closed && vertex_inside(b, a)) return true;
    return false;
}

TriangleMesh load_obj(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError({path, 0, 0}, "", "cannot open the mesh file");
    std::stringstream buf;
    buf << in.rdbuf();
    const std::string text = buf.str();
    // Vertex lines first, by our own parser: tinyobjloader reads "nan" or garbage as numbers
    // without a word; every coordinate must be a finite number.
    {
        std::istringstream lines(text);
        std::string line;
        int n = 0;
        while (std::getline(lines, line)) {
            ++n;
            if (line.size() < 2 || line[0] != 'v' || (line[1] != ' ' && line[1] != '\t')) continue;
            const char* p = line.c_str() + 1;
            for (int k = 0; k < 3; ++k) {
                char* end = nullptr;
                const double v = std::strtod(p, &end);
                if (end == p || !std::isfinite(v))
                    throw InputError({path, n, 0}, "v",
                                     end == p ? "expected three coordinates after 'v'"
                                              : "vertex coordinate is not finite",
                                     line);
                p = end;
            }
        }
    }
    tinyobj::ObjReader reader;
    tinyobj::ObjReaderConfig config;
    config.triangulate = true;
    config.vertex_color = false;
    if (!reader.ParseFromString(text, "", config) || !reader.Error().empty()) {
        const std::string msg =
            reader.Error().empty() ? "cannot parse" : first_line(reader.Error());
        const int line = line_in(reader.Error());
        throw InputError({path, line, 0}, "", "OBJ: " + msg, read_source_line(path, line));
    }
    if (!reader.Warning().empty() && reader.Warning().find("out of bounds") != std::string::npos) {
        const int line = line_in(reader.Warning());
        throw InputError({path, line, 0}, "f", "OBJ: " + first_line(reader.Warning()),
                         read_source_line(path, line));
    }
    TriangleMesh m;
    const auto& v = reader.GetAttrib().vertices;
    for (std::size_t i = 0; i + 2 < v.size(); i += 3)
        m.positions.push_back({v[i], v[i + 1], v[i + 2]});
    for (const tinyobj::shape_t& s : reader.GetShapes()) {
        const auto& ix = s.mesh.indices;
        std::size_t k = 0;
        for (const unsigned char fv : s.mesh.num_face_vertices) {
            if (fv != 3)
                throw InputError({path, 0, 0}, "f", "OBJ: a face could not be triangulated");
            Tri t{};
            for (int j = 0; j < 3; ++j) {
                const int vi = ix[k + static_cast<size_t>(j)].vertex_index;
                if (vi < 0 || static_cast<std::size_t>(vi) >= m.positions.size())
                    throw InputError({path, 0, 0}, "f", "OBJ: face index out of range");
                t[static_cast<size_t>(j)] = static_cast<std::uint32_t>(vi);
            }
            m.triangles.push_back(t);
            k += 3;
        }
    }
    if (m.triangles.empty()) throw InputError({path, 0, 0}, "f", "OBJ: no faces");
    return m;
}

std::string to_obj(const TriangleMesh& m) {
    std::string s = "# written by ssslab\n";
    char buf[128];
    for (const Vec3& p : m.positions) {
        std::snprintf(buf, sizeof buf, "v %.17g %.17g %.17g\n", p.x, p.y, p.z);
        s += buf;
    }
    for (const Tri& t : m.triangles) {
        std::snprintf(buf, sizeof buf, "f %" PRIu32 " %" PRIu32 " %" PRIu32 "\n", t[0] + 1,
                      t[1] + 1, t[2] + 1);
        s += buf;
    }
    return s;
}

}  // namespace ssslab
