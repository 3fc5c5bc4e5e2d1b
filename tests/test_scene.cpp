// Scene files and meshes (core/scene.h, core/mesh.h): procedural shapes against their closed-form
// areas and volumes, the topology check, OBJ reading, and every kind of bad scene refused with
// file, line and key before anything renders.
#include "core/error.h"
#include "core/mesh.h"
#include "core/scene.h"
#include "testing.h"

#include <gtest/gtest.h>
#include <toml++/toml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <set>

namespace ssslab {
namespace {

namespace fs = std::filesystem;
constexpr double kPi = std::numbers::pi;

// ---- meshes -------------------------------------------------------------------------------------

TEST(Mesh, ProceduralShapesAreClosedAndMatchTheirClosedForms) {
    // Icosphere: an inscribed polyhedron, so area and volume approach 4 pi r^2 and 4/3 pi r^3
    // from below, with an error falling 4x per subdivision (edge length halves).
    double prev_err = 1;
    for (int s = 1; s <= 5; ++s) {
        const TriangleMesh m = make_sphere(2.0, s);
        EXPECT_TRUE(check_mesh(m).closed()) << check_mesh(m).describe();
        EXPECT_EQ(m.triangles.size(), 20u << (2 * s));
        const double err = 1 - m.volume() / (4.0 / 3.0 * kPi * 8.0);
        EXPECT_GT(err, 0);
        EXPECT_LT(err, 0.3 * prev_err + 1e-12) << s;
        prev_err = err;
        EXPECT_LT(1 - m.area() / (4 * kPi * 4.0), 2 * err + 1e-12);
    }
    EXPECT_LT(prev_err, 2e-3);
    const TriangleMesh box = make_box({1, 2, 3});
    EXPECT_TRUE(check_mesh(box).closed());
    EXPECT_NEAR(box.volume(), 6.0, 1e-14);
    EXPECT_NEAR(box.area(), 2 * (2 + 6 + 3), 1e-14);
    // Torus: Pappus's V = 2 pi^2 R r^2 and A = 4 pi^2 R r, to the tessellation's 0.3 %.
    const TriangleMesh torus = make_torus(3.0, 1.0, 128, 64);
    EXPECT_TRUE(check_mesh(torus).closed()) << check_mesh(torus).describe();
    EXPECT_NEAR(torus.volume() / (2 * kPi * kPi * 3.0 * 1.0), 1.0, 3e-3);
    EXPECT_NEAR(torus.area() / (4 * kPi * kPi * 3.0 * 1.0), 1.0, 3e-3);
    const TriangleMesh quad = make_quad(2, 5);
    EXPECT_EQ(check_mesh(quad).boundary_edges, 4u);
    EXPECT_NEAR(quad.area(), 10.0, 1e-14);
    const Vec3 n =
        cross(quad.positions[quad.triangles[0][1]] - quad.positions[quad.triangles[0][0]],
              quad.positions[quad.triangles[0][2]] - quad.positions[quad.triangles[0][0]]);
    EXPECT_GT(n.y, 0);  // faces +y
    const TriangleMesh bumpy = make_bumpy_sphere(1.0, 0.1, 6.0, 7, 5);
    EXPECT_TRUE(check_mesh(bumpy).closed());
    double rmin = 10, rmax = 0;
    for (const Vec3& p : bumpy.positions) {
        rmin = std::min(rmin, length(p));
        rmax = std::max(rmax, length(p));
    }
    EXPECT_GE(rmin, 0.9 - 1e-12);
    EXPECT_LE(rmax, 1.1 + 1e-12);
    EXPECT_GT(rmax - rmin, 0.05);  // there is detail
    EXPECT_EQ(make_bumpy_sphere(1.0, 0.1, 6.0, 7, 3).positions,
              make_bumpy_sphere(1.0, 0.1, 6.0, 7, 3).positions);  // deterministic
    EXPECT_NE(make_bumpy_sphere(1.0, 0.1, 6.0, 8, 3).positions,
              make_bumpy_sphere(1.0, 0.1, 6.0, 7, 3).positions);
}

TEST(Mesh, TransformsKeepOrientationAndScaleVolume) {
    const TriangleMesh box = make_box({1, 1, 1});
    Transform t;
    t.scale = {2, -1, 3};  // mirrors: the winding is flipped back
    t.rotate_deg = {30, 45, 60};
    t.translate = {5, -2, 1};
    const TriangleMesh m = transformed(box, t);
    EXPECT_TRUE(check_mesh(m).closed());
    EXPECT_NEAR(m.volume(), 6.0, 1e-12);
    // Rotations about x, y, z in turn: (1, 0, 0) by 90 deg about z goes to (0, 1, 0).
    Transform r;
    r.rotate_deg = {0, 0, 90};
    const Vec3 p = r.apply({1, 0, 0});
    EXPECT_NEAR(p.x, 0, 1e-15);
    EXPECT_NEAR(p.y, 1, 1e-15);
}

TEST(Mesh, TopologyCheckFindsHolesFlipsAndNonFiniteVertices) {
    TriangleMesh m = make_box({1, 1, 1});
    m.triangles.pop_back();
    EXPECT_EQ(check_mesh(m).boundary_edges, 3u);
    EXPECT_FALSE(check_mesh(m).closed());
    m = make_box({1, 1, 1});
    std::swap(m.triangles[0][1], m.triangles[0][2]);
    EXPECT_GT(check_mesh(m).inconsistent_edges, 0u);
    EXPECT_NE(check_mesh(m).describe().find("flipped"), std::string::npos);
    m = make_box({1, 1, 1});
    m.positions[5].y = std::nan("");
    EXPECT_EQ(check_mesh(m).nonfinite_vertices, 1u);
    EXPECT_EQ(check_mesh(m).first_nonfinite_vertex, 5u);
    m = make_box({1, 1, 1});
    m.triangles.push_back(m.triangles[0]);  // a third triangle on three edges
    EXPECT_GT(check_mesh(m).nonmanifold_edges, 0u);
}

TEST(Mesh, InsideAndOverlapTests) {
    const TriangleMesh s = make_sphere(1.0, 3);
    EXPECT_TRUE(inside_mesh(s, {0, 0, 0}));
    EXPECT_TRUE(inside_mesh(s, {0.9, 0.1, -0.2}));
    EXPECT_FALSE(inside_mesh(s, {1.1, 0, 0}));
    EXPECT_FALSE(inside_mesh(s, {0, 5, 0}));
    const TriangleMesh box = make_box({1, 1, 1});
    EXPECT_TRUE(inside_mesh(box, {0.49, -0.49, 0.2}));
    EXPECT_FALSE(inside_mesh(box, {0.51, 0, 0}));
    auto moved = [](const TriangleMesh& m, Vec3 t) {
        return transformed(m, {{1, 1, 1}, {0, 0, 0}, t});
    };
    EXPECT_TRUE(meshes_overlap(s, true, moved(s, {1.5, 0, 0}), true));    // crossing surfaces
    EXPECT_FALSE(meshes_overlap(s, true, moved(s, {2.05, 0, 0}), true));  // apart
    EXPECT_TRUE(meshes_overlap(transformed(s, {{0.2, 0.2, 0.2}, {0, 0, 0}, {0, 0, 0}}), true, s,
                               true));  // nested
    const TriangleMesh floor = make_quad(10, 10);
    EXPECT_TRUE(meshes_overlap(s, true, floor, false));                        // through the floor
    EXPECT_FALSE(meshes_overlap(moved(s, {0, 1.01, 0}), true, floor, false));  // resting above it
}

TEST(Mesh, ObjRoundTripAndBadFiles) {
    testing::TempDir dir;
    const TriangleMesh sphere = make_sphere(1.5, 2);
    dir.write("s.obj", to_obj(sphere));
    const TriangleMesh back = load_obj((dir / "s.obj").string());
    EXPECT_EQ(back.positions.size(), sphere.positions.size());
    EXPECT_EQ(back.triangles, sphere.triangles);
    for (size_t i = 0; i < back.positions.size(); ++i)
        EXPECT_NEAR(length(back.positions[i] - sphere.positions[i]), 0, 1e-6);  // float storage
    // A quad face is triangulated; groups and comments are fine.
    dir.write("q.obj", "# quad\no thing\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\ng g1\nf 1 2 3 4\n");
    EXPECT_EQ(load_obj((dir / "q.obj").string()).triangles.size(), 2u);
    struct Bad {
        const char* text;
        const char* expect;
    };
    const Bad bad[] = {
        {"v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n", "b.obj:3"},
        {"v 0 0 0\nv 1 0 inf\nv 0 1 0\nf 1 2 3\n", "not finite"},
        {"v 0 0\nf 1 2 3\n", "three coordinates"},
        {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n", "b.obj"},
        {"v 0 0 0\nv 1 0 0\n", "no faces"},
    };
    for (const Bad& b : bad) {
        SCOPED_TRACE(b.text);
        dir.write("b.obj", b.text);
        try {
            (void)load_obj((dir / "b.obj").string());
            ADD_FAILURE() << "accepted";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(b.expect), std::string::npos) << e.what();
        }
    }
    EXPECT_THROW((void)load_obj((dir / "missing.obj").string()), InputError);
}

// ---- scenes -------------------------------------------------------------------------------------

const char* kScene = R"(
[scene]
name = "test"
unit_mm = 1.0

[camera]
position = [0, 5, 40]
target = [0, 0, 0]
fov_y_deg = 30
width = 64
height = 48

[[lights]]
type = "directional"
direction = [1, 1, 1]
irradiance = [1, 1, 1]
angular_radius_deg = 0.5

[[lights]]
type = "environment"
radiance = 0.1

[[materials]]
name = "skin"
preset = "Skin1"
roughness = 0.1

[[materials]]
name = "milk"
sigma_a_per_mm = [0.0011, 0.0024, 0.014]
sigma_s_per_mm = [2.55, 3.21, 3.77]
g = 0.5
eta = 1.3

[[materials]]
name = "floor"
type = "diffuse"
albedo = [0.5, 0.5, 0.5]

[[shapes]]
type = "sphere"
radius = 5
translate = [0, 5.1, 0]
material = "skin"

[[shapes]]
type = "torus"
major_radius = 4
minor_radius = 1
segments_major = 48
segments_minor = 24
rotate_deg = [90, 0, 0]
translate = [12, 2, 0]
material = "milk"

[[shapes]]
type = "plane"
size_x = 100
size_z = 100
material = "floor"
)";

TEST(Scene, ReadsCameraLightsMaterialsAndShapes) {
    const Scene s = parse_scene(kScene, "t.toml", ".");
    EXPECT_EQ(s.name, "test");
    EXPECT_EQ(s.camera.width, 64);
    EXPECT_EQ(s.camera.height, 48);
    ASSERT_EQ(s.lights.size(), 2u);
    EXPECT_NEAR(length(s.lights[0].direction), 1.0, 1e-15);
    EXPECT_EQ(s.lights[1].type, LightType::kEnvironment);
    EXPECT_EQ(s.lights[1].color[2], 0.1);
    ASSERT_EQ(s.materials.size(), 3u);
    EXPECT_EQ(s.materials[0].medium.sigma_a_per_cm, find_material("Skin1")->sigma_a_per_cm);
    EXPECT_DOUBLE_EQ(s.materials[1].medium.sigma_s_per_cm[0], 25.5);  // per mm -> per cm
    EXPECT_DOUBLE_EQ(s.per_world_unit(s.materials[1].medium.sigma_s_per_cm[0]), 2.55);
    EXPECT_EQ(s.materials[2].kind, SceneMaterial::Kind::kDiffuse);
    ASSERT_EQ(s.shapes.size(), 3u);
    EXPECT_TRUE(s.shapes[0].exact_sphere);
    EXPECT_EQ(s.shapes[0].center, (Vec3{0, 5.1, 0}));
    EXPECT_EQ(s.shapes[0].radius, 5);
    EXPECT_EQ(s.shapes[1].mesh.triangles.size(), 48u * 24u * 2u);
    const auto b = s.shapes[1].mesh.bounds();  // rotated from the x-y into the x-z plane
    EXPECT_NEAR(b[1].y - b[0].y, 2.0, 1e-2);
    EXPECT_NEAR(b[1].z - b[0].z, 10.0, 1e-2);
    EXPECT_TRUE(s.has_media());
    EXPECT_FALSE(s.delta_light_through_smooth_boundary());  // rough skin, smooth milk, no delta
    EXPECT_NE(describe(s).find("torus"), std::string::npos);
}

TEST(Scene, TheResolvedSceneHoldsTheMediaAsSimulated) {
    // A preset by name and explicit coefficients alike: the resolved scene (what outputs write
    // beside them) holds the coefficients per cm, g, eta and the boundary's GGX alpha that the
    // engines use. Skin1 of Freude14 Table 6.2: sigma_a 0.032, 0.17, 0.48 and sigma_s 0.74,
    // 0.88, 1.01 per mm, g 0, eta 1.3; roughness 0.1 here.
    const Scene s = parse_scene(kScene, "t.toml", ".");
    const toml::table t = toml::parse(s.resolved_toml);
    const auto skin = t["materials"][0]["simulated"];
    const double sa[3] = {0.32, 1.7, 4.8}, ss[3] = {7.4, 8.8, 10.1};
    for (int c = 0; c < 3; ++c) {
        EXPECT_DOUBLE_EQ(skin["sigma_a_per_cm"][c].value_or(-1.0), sa[c]);
        EXPECT_DOUBLE_EQ(skin["sigma_s_per_cm"][c].value_or(-1.0), ss[c]);
        EXPECT_EQ(skin["g"][c].value_or(-1.0), 0.0);
    }
    EXPECT_EQ(skin["eta"].value_or(0.0), 1.3);
    EXPECT_EQ(skin["ggx_alpha"].value_or(-1.0), 0.1);
    const auto milk = t["materials"][1]["simulated"];
    EXPECT_DOUBLE_EQ(milk["sigma_s_per_cm"][0].value_or(-1.0), 25.5);
    EXPECT_EQ(milk["ggx_alpha"].value_or(-1.0), 0.0);
    EXPECT_FALSE(t["materials"][2]["simulated"]) << "a diffuse material has no medium";
}

TEST(Scene, DeltaLightThroughASmoothBoundaryIsFlagged) {
    std::string t = kScene;
    t.replace(t.find("angular_radius_deg = 0.5"), 24, "angular_radius_deg = 0.0");
    EXPECT_TRUE(parse_scene(t, "t.toml", ".").delta_light_through_smooth_boundary());  // milk
}

TEST(Scene, MeshShapesReadObjRelativeToTheSceneFile) {
    testing::TempDir dir;
    fs::create_directories(dir / "meshes");
    dir.write("meshes/blob.obj", to_obj(make_sphere(2.0, 2)));
    std::string t = kScene;
    t += "\n[[shapes]]\ntype = \"mesh\"\nfile = \"meshes/blob.obj\"\nscale = 2\n"
         "translate = [-20, 5, 0]\nmaterial = \"milk\"\n";
    dir.write("scene.toml", t);
    const Scene s = read_scene((dir / "scene.toml").string());
    ASSERT_EQ(s.shapes.size(), 4u);
    EXPECT_EQ(s.shapes[3].mesh.triangles.size(), 320u);
    EXPECT_NEAR(s.shapes[3].mesh.bounds()[1].x, -16.0, 1e-6);
}

TEST(Scene, BadScenesAreRefusedWithFileLineAndKey) {
    testing::TempDir dir;
    dir.write("open.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    dir.write("nan.obj", "v 0 0 0\nv 1 0 0\nv 0 nan 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\n");
    auto with = [](const std::string& from, const std::string& to) {
        std::string t = kScene;
        const size_t i = t.find(from);
        EXPECT_NE(i, std::string::npos) << from;
        return t.replace(i, from.size(), to);
    };
    struct Case {
        const char* what;
        std::string text;
        std::vector<std::string> expect;
    };
    const std::vector<Case> cases = {
        {"unknown key",
         with("fov_y_deg = 30", "fov_y_deg = 30\nfov = 3"),
         {"s.toml:10:1", "camera.fov"}},
        {"typo in a key",
         with("irradiance = [1, 1, 1]", "irradiance = [1, 1, 1]\nangular_radius = 1"),
         {"s.toml:", "did you mean 'angular_radius_deg'"}},
        {"negative coefficient",
         with("sigma_a_per_mm = [0.0011", "sigma_a_per_mm = [-0.0011"),
         {"s.toml:", "materials[1].sigma_a_per_mm"}},
        {"NaN in a vector",
         with("position = [0, 5, 40]", "position = [0, nan, 40]"),
         {"s.toml:7:", "camera.position", "finite"}},
        {"open mesh bound to a medium",
         with("material = \"floor\"", "material = \"milk\""),
         {"s.toml:", "shapes[2].material", "closed", "boundary edges"}},
        {"open OBJ bound to a medium",
         std::string(kScene) +
             "[[shapes]]\ntype = \"mesh\"\nfile = \"open.obj\"\nmaterial = \"skin\"\n",
         {"shapes[3].material", "3 boundary edges"}},
        {"NaN vertex in an OBJ",
         std::string(kScene) +
             "[[shapes]]\ntype = \"mesh\"\nfile = \"nan.obj\"\nmaterial = \"floor\"\n",
         {"nan.obj:3", "not finite"}},
        {"missing OBJ",
         std::string(kScene) +
             "[[shapes]]\ntype = \"mesh\"\nfile = \"none.obj\"\nmaterial = \"floor\"\n",
         {"shapes[3].file", "not found"}},
        {"unknown material",
         with("material = \"floor\"", "material = \"flor\""),
         {"shapes[2].material", "unknown material \"flor\" (did you mean \"floor\"?)",
          "the scene's materials: floor, milk, skin"}},
        {"unknown material, nothing near",
         with("material = \"floor\"", "material = \"granite\""),
         {"shapes[2].material", "unknown material \"granite\"; the scene's materials"}},
        // Items of a list: the column and the caret are the bad item's, not the '['.
        {"g = 1 in a list",
         with("\ng = 0.5", "\ng = [0.5, 1.0, 0.5]"),
         {"s.toml:32:11: error: key 'materials[1].g'", "(-1, 1)",
          "\n    g = [0.5, 1.0, 0.5]\n              ^"}},
        {"a scale factor of 0 in a list",
         with("radius = 5\n", "radius = 5\nscale = [1, 1, 0]\n"),
         {"s.toml:43:16: error: key 'shapes[0].scale'", "must not be 0",
          "\n    scale = [1, 1, 0]\n                   ^"}},
        {"unknown shape type",
         with("type = \"torus\"", "type = \"taurus\""),
         {"shapes[1].type", "torus"}},
        {"up parallel to the view",
         with("target = [0, 0, 0]", "target = [0, 0, 0]\nup = [0, -5, -40]"),
         {"camera.up", "parallel"}},
        {"misspelt light key",
         with("type = \"directional\"", "tipe = \"directional\""),
         {"lights[0].tipe", "did you mean 'type'"}},
        {"spot: inner cone wider than the outer",
         std::string(kScene) +
             "[[lights]]\ntype = \"spot\"\nposition = [0, 20, 0]\ndirection = [0, -1, 0]\n"
             "intensity = [1, 1, 1]\ninner_cone_angle_deg = 30\nouter_cone_angle_deg = 20\n",
         {"lights[2].inner_cone_angle_deg", "[0, 20)"}},
        {"spot: no direction",
         std::string(kScene) +
             "[[lights]]\ntype = \"spot\"\nposition = [0, 20, 0]\nintensity = [1, 1, 1]\n",
         {"lights[2].direction"}},
        {"unknown light type",
         with("type = \"directional\"", "type = \"spotlight\""),
         {"lights[0].type", "spot"}},
        {"g = 1", with("\ng = 0.5", "\ng = 1.0"), {"materials[1].g", "(-1, 1)"}},
        {"albedo 1",
         with("albedo = [0.5, 0.5, 0.5]", "albedo = [0.5, 1.0, 0.5]"),
         {"materials[2].albedo"}},
        {"torus tube too fat", with("minor_radius = 1", "minor_radius = 4"), {"minor_radius"}},
        {"duplicate material", with("name = \"milk\"", "name = \"skin\""), {"defined twice"}},
        {"media overlapping",
         with("translate = [12, 2, 0]", "translate = [4, 4, 0]"),
         {"s.toml:", "shapes[1]", "intersect"}},
        {"medium sunk into the floor",
         with("translate = [0, 5.1, 0]", "translate = [0, 4, 0]"),
         {"shapes[2]", "intersect"}},
        {"camera inside a medium",
         with("position = [0, 5, 40]", "position = [0, 5, 1]"),
         {"camera.position", "inside"}},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.what);
        dir.write("s.toml", c.text);
        try {
            (void)read_scene((dir / "s.toml").string());
            ADD_FAILURE() << "accepted";
        } catch (const InputError& e) {
            for (const std::string& x : c.expect)
                EXPECT_NE(std::string(e.what()).find(x), std::string::npos) << x << "\n"
                                                                            << e.what();
        }
    }
}

TEST(Scene, BuiltInScenesLoadWithMediaBehindConvergingBoundariesAndLights) {
    // The five main materials of Freude14 ch. 6 each have a scene; each binds its medium to
    // closed meshes and avoids a delta light through a smooth boundary (issue: use what
    // converges).
    std::set<std::string> names;
    for (const auto& e : fs::directory_iterator(testing::source_path("experiments/scenes"))) {
        if (e.path().extension() != ".toml") continue;
        SCOPED_TRACE(e.path().string());
        const Scene s = read_scene(e.path().string());
        names.insert(s.name);
        EXPECT_TRUE(s.has_media());
        EXPECT_FALSE(s.delta_light_through_smooth_boundary());
        EXPECT_EQ(s.camera.width, 512);
    }
    for (const char* n : {"skin", "marble", "wholemilk", "apple", "ketchup"})
        EXPECT_EQ(names.count(n), 1u) << n;
}

TEST(Scene, CommandValidatesAndExportsOrWritesNothing) {
    testing::TempDir dir;
    dir.write("s.toml", kScene);
    const auto ok = testing::run_ssslab({"scene", "s.toml", "--export-obj", "out"}, dir.path());
    ASSERT_EQ(ok.exit_code, 0) << ok.err;
    EXPECT_NE(ok.out.find("3 shapes"), std::string::npos) << ok.out;
    EXPECT_TRUE(fs::exists(dir / "out" / "test" / "shapes_1_.obj"));
    const TriangleMesh torus = load_obj((dir / "out" / "test" / "shapes_1_.obj").string());
    EXPECT_EQ(torus.triangles.size(), 48u * 24u * 2u);
    // scene.json for other renderers: coefficients per world unit, the lights in scene units.
    const std::string json = testing::read_text(dir / "out" / "test" / "scene.json");
    // ... with what produced it.
    for (const char* k : {"\"source\"", "\"content_key\"", "\"git_revision\"", "\"command_line\""})
        EXPECT_NE(json.find(k), std::string::npos) << k << "\n" << json;
    auto numbers_after = [&](const std::string& from, const std::string& key) {
        std::vector<double> v;
        size_t at = json.find(key, json.find(from));
        if (at == std::string::npos) return v;
        const char* p = json.c_str() + json.find('[', at) + 1;
        for (int i = 0; i < 3; ++i) {
            char* end = nullptr;
            v.push_back(std::strtod(p, &end));
            p = end + 1;
        }
        return v;
    };
    const auto ss = numbers_after("\"milk\"", "sigma_s_per_unit");
    ASSERT_EQ(ss.size(), 3u) << json;
    EXPECT_NEAR(ss[0], 2.55, 1e-12);  // per mm, and a world unit is 1 mm
    EXPECT_NEAR(ss[2], 3.77, 1e-12);
    const auto sun = numbers_after("directional", "irradiance");
    ASSERT_EQ(sun.size(), 3u) << json;
    EXPECT_DOUBLE_EQ(sun[1], 1.0);
    EXPECT_NE(json.find("\"obj\": \"shapes_1_.obj\""), std::string::npos) << json;
    EXPECT_NE(json.find("\"ggx_alpha\": 0.10000000000000001"), std::string::npos) << json;
    // A bad second scene: nothing is written.
    testing::TempDir dir2;
    dir2.write("a.toml", kScene);
    std::string bad = kScene;
    bad.replace(bad.find("radius = 5"), 10, "radius = -5");
    dir2.write("b.toml", bad);
    const auto r =
        testing::run_ssslab({"scene", "a.toml", "b.toml", "--export-obj", "out"}, dir2.path());
    EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
    EXPECT_NE(r.err.find("b.toml:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("shapes[0].radius"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir2 / "out"));
}

}  // namespace
}  // namespace ssslab
