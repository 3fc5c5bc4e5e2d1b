// Golden-seed pins of the path tracer's engines and of MCML's default engine (issue 14): with a
// fixed seed each engine's result is a deterministic function of its random-number order, so a
// refactoring that keeps that order (the one medium walk of volpath/walk.h replacing the four
// copies; MCML's batch loop moved onto core/batch_runner) must reproduce it to rounding. These are
// regression pins, not evidence of correctness: the values were written by the engine versions
// named beside them (volpath-pencil-2, volpath-sphere-3, volpath-render-3, whose estimator
// volpath-render-4 keeps as options) before the walk was moved, MCML's by mcml-default-3 with its
// own driver before it moved onto the shared one, volpath-render-4's by itself when it was made
// (its agreement with the old estimator: Render.NewerEstimatorsAgreeWithTheLegacyOne), and
// are compared with a relative tolerance of 1e-9 (a different random-number order moves them by
// ~1e-3; rounding by ~1e-15). Correctness is what the closed-form and cross-engine tests show. An
// engine change that alters the numbers bumps the engine's version and re-pins here, after showing
// (in the tests of that engine) that the old and new results agree statistically; a failure prints
// the new values. volpath-pencil-3 and volpath-sphere-4 changed only the default batch size of
// small budgets (32 batches, core's default_batch_samples); these pins set their batch sizes, so
// their values stand.
#include "core/material.h"
#include "core/scene.h"
#include "mcml/engine.h"
#include "mcml/mci.h"
#include "volpath/pencil.h"
#include "volpath/render.h"
#include "volpath/sphere.h"

#include "testing.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace ssslab::volpath {
namespace {

void expect_pinned(const std::string& what, const std::vector<double>& got,
                   const std::vector<double>& pinned) {
    bool same = got.size() == pinned.size();
    for (std::size_t i = 0; same && i < got.size(); ++i)
        same = same && std::fabs(got[i] - pinned[i]) <= 1e-9 * std::fabs(pinned[i]) + 1e-300;
    if (same) return;
    std::string text;
    for (double v : got) {
        char buf[40];
        std::snprintf(buf, sizeof buf, "%.17g, ", v);
        text += buf;
    }
    ADD_FAILURE() << what << ": the engine's numbers moved; now {" << text << "}";
}

// The tally of a run folded into a few numbers that move with any change of a path: the
// totals and the first moment of every block of `block` elements.
std::vector<double> fold(const std::vector<double>& mean, std::size_t block) {
    std::vector<double> out;
    for (std::size_t b = 0; b < mean.size(); b += block) {
        double sum = 0, moment = 0;
        for (std::size_t i = b; i < std::min(mean.size(), b + block); ++i) {
            sum += mean[i];
            moment += mean[i] * static_cast<double>(i - b + 1);
        }
        out.push_back(sum);
        out.push_back(moment);
    }
    return out;
}

Medium chromatic() {
    Medium m;
    m.name = "golden";
    m.sigma_a_per_cm = {0.5, 1.0, 2.0};
    m.sigma_s_per_cm = {10.0, 30.0, 80.0};
    m.g = {0.0, 0.5, 0.9};
    m.eta = 1.4;
    return m;
}

std::vector<double> pencil(const Medium& m, ChromaticMode mode, Absorption a, HeroSelection h,
                           FlightRule f = FlightRule::kContinue) {
    PencilOptions o;
    o.seed = 7;
    o.budget.samples = 6000;
    o.batch_paths = 1000;
    o.mode = mode;
    o.absorption = a;
    o.hero_selection = h;
    o.flight = f;
    const PencilRun r = simulate_pencil(m, {0.05, 20}, o);
    std::vector<double> out;
    for (const BatchRunResult& run : r.runs)
        for (double v : fold(run.mean, r.layout.per_channel())) out.push_back(v);
    return out;
}

TEST(WalkGolden, PencilEngineVolpathPencil2) {
    const Medium m = chromatic();
    expect_pinned(
        "pencil per-channel analog",
        pencil(m, ChromaticMode::kPerChannel, Absorption::kAnalog, HeroSelection::kUniform),
        {0.85944444444444645, 30.581087962963093, 0.67245370370370539, 22.909606481481585,
         0.27578703703703744, 9.3787037037037315});
    expect_pinned(
        "pencil per-channel weighted",
        pencil(m, ChromaticMode::kPerChannel, Absorption::kWeighted, HeroSelection::kUniform),
        {0.84135668835367183, 29.901811399010167, 0.66092628390792385, 22.50476919827884,
         0.26861278928455257, 9.1303665167052266});
    expect_pinned("pencil hero analog uniform",
                  pencil(m, ChromaticMode::kHero, Absorption::kAnalog, HeroSelection::kUniform),
                  {0.84852609451174876, 30.206085820430843, 0.64115242053019539, 21.876123286708147,
                   0.28073815162472282, 9.524596448416581});
    expect_pinned(
        "pencil hero analog mfp",
        pencil(m, ChromaticMode::kHero, Absorption::kAnalog, HeroSelection::kMeanFreePath),
        {0.83212651348159006, 29.707263666931244, 0.66488751702866633, 22.646417601093507,
         0.2853929345201196, 9.6946088645848594});
    expect_pinned("pencil hero weighted",
                  pencil(m, ChromaticMode::kHero, Absorption::kWeighted, HeroSelection::kUniform),
                  {0.85264354914354057, 30.420113319155504, 0.65586462421249692, 22.383859965782666,
                   0.24925548398795824, 8.4934510174696989});
    expect_pinned("pencil hero resample",
                  pencil(m, ChromaticMode::kHero, Absorption::kAnalog, HeroSelection::kUniform,
                         FlightRule::kResample),
                  {0.85776028014425765, 30.569389716230607, 0.65957523660878248, 22.451943517423899,
                   0.25988670546918197, 8.8435973219010542});
    // A finite stack under a clear top layer (MCML's entry), index steps between the layers.
    Medium s = chromatic();
    s.thickness_cm = 0.05;
    s.sigma_a_per_cm = {0, 0, 0};
    s.sigma_s_per_cm = {0, 0, 0};
    s.eta = 1.5;
    MediumLayer mid;
    mid.sigma_a_per_cm = {1.0, 2.0, 3.0};
    mid.sigma_s_per_cm = {20.0, 40.0, 60.0};
    mid.g = {0.8, 0.8, 0.8};
    mid.eta = 1.37;
    mid.thickness_cm = 0.1;
    MediumLayer low = mid;
    low.sigma_s_per_cm = {50.0, 50.0, 50.0};
    low.g = {0.0, 0.3, 0.6};
    low.eta = 1.45;
    low.thickness_cm = 0.2;
    s.lower_layers = {mid, low};
    s.eta_below = 1.2;
    expect_pinned(
        "pencil stack per-channel",
        pencil(s, ChromaticMode::kPerChannel, Absorption::kAnalog, HeroSelection::kUniform),
        {0.72305289414178286, 27.127577686085367, 0.43498146723547132, 15.982694594027574,
         0.31202415087302121, 11.489482947525456});
    expect_pinned("pencil stack hero",
                  pencil(s, ChromaticMode::kHero, Absorption::kAnalog, HeroSelection::kUniform),
                  {0.69369861026124158, 25.779443878467323, 0.40077404739594791, 14.560810294278582,
                   0.31586372950275171, 11.496314818092623});
}

std::vector<double> sphere(ChromaticMode mode) {
    SphereScene sc;
    sc.medium = chromatic();
    sc.radius_cm = 0.2;
    sc.to_light = {0, 0, 1};
    sc.to_camera = {1, 0, 1};
    sc.width = 8;
    sc.height = 8;
    sc.beta_bins = 18;
    SphereOptions o;
    o.seed = 9;
    o.budget.samples = 6000;
    o.batch_paths = 1002;
    o.mode = mode;
    o.image = true;
    const SphereRun r = simulate_sphere(sc, o);
    std::vector<double> out;
    for (const BatchRunResult& run : r.runs)
        for (double v : fold(run.mean, r.layout.per_channel())) out.push_back(v);
    return out;
}

TEST(WalkGolden, SphereEngineVolpathSphere3) {
    expect_pinned("sphere per-channel", sphere(ChromaticMode::kPerChannel),
                  {2.0282849899824185, 47.438040056600684, 1.514180150555301, 36.097498998944317,
                   1.0069233765648524, 23.16190166081126});
    expect_pinned("sphere hero", sphere(ChromaticMode::kHero),
                  {2.0591782431419805, 49.629563149808476, 1.4982147624100786, 36.579527588645128,
                   0.95767601236557531, 21.797494205516589});
}

// legacy: the estimator of volpath-render-3 (one light per NEE, the stream alone, batches of 3
// spp), which volpath-render-4 keeps as options; otherwise the defaults. `absorption`: as the
// pinned version had it (volpath-render-5 chooses per medium). Before volpath-render-6 (v6
// false): the hero in turn and the environment sampled over the sphere, as those versions had
// them; before volpath-render-7 (v7 false) rays leaving a surface start eps off it; before
// volpath-render-8 (guide false) no exit guides (they change only media behind rough boundaries
// with the same g in all channels); before volpath-render-9 (boundary_guides false) none at the
// boundary's vertices; before volpath-render-10 (diffuse_guides false) none at diffuse ones;
// before volpath-render-11 (wide_lobes false) one lobe per light.
std::vector<double> render_pin(const std::string& material, const std::string& lights, bool legacy,
                               std::optional<Absorption> absorption = Absorption::kAnalog,
                               bool v6 = false, bool v7 = false, bool guide = false,
                               bool boundary_guides = false, bool diffuse_guides = false,
                               bool wide_lobes = false) {
    const std::string text = R"(
[scene]
name = "golden"
[camera]
position = [0, 2, 10]
target = [0, 0, 0]
fov_y_deg = 30
width = 12
height = 12
)" + lights + material + R"(
[[materials]]
name = "floor"
type = "diffuse"
albedo = [0.6, 0.5, 0.4]
[[shapes]]
type = "sphere"
radius = 1.5
subdivisions = 3
material = "m"
[[shapes]]
type = "box"
size = [20, 1, 20]
translate = [0, -2.1, 0]
material = "floor"
)";
    const Scene s = parse_scene(text, "golden.toml", ".");
    RenderOptions o;
    o.seed = 11;
    o.budget.samples = 12;
    o.absorption = absorption;
    if (!v6) {
        o.hero = RenderHero::kUniform;
        o.environment_cosine = false;
    }
    o.rays_from_surface = v7;
    o.exit_guide = guide;
    o.boundary_guides = boundary_guides;
    o.diffuse_guides = diffuse_guides;
    o.wide_lobes = wide_lobes;
    if (legacy) {
        o.nee_all_lights = false;
        o.sampler = RenderSampler::kIndependent;
        o.batch_spp = 3;
    }
    const RenderResult r = render(s, o);
    return fold(r.run.mean, r.run.mean.size() / 4);
}

// The pinned render scenes: a sphere light and an environment, a chromatic medium.
const std::string kLights =
    "[[lights]]\ntype = \"sphere\"\nposition = [4, 4, 3]\nradius = 1\nradiance = 5\n"
    "[[lights]]\ntype = \"environment\"\nradiance = 0.2\n";
const std::string kCoefficients =
    "[[materials]]\nname = \"m\"\nsigma_a_per_mm = [0.05, 0.1, 0.2]\n"
    "sigma_s_per_mm = [1.0, 3.0, 8.0]\ng = [0.0, 0.5, 0.9]\n";

// volpath-render-4 with the legacy options (one light per NEE, the stream alone, batches of 3
// spp) is volpath-render-3 but for one fix: a sphere light now blocks the shadow rays of the other
// lights. The smooth boundary (no NEE at its first vertex) is volpath-render-3's pin; the rough
// and index-matched ones were re-pinned with the fix (it moved their blocks by up to 9e-6 and
// 8e-4 relative).
TEST(WalkGolden, RenderEngineVolpathRender3) {
    expect_pinned("render rough boundary",
                  render_pin(kCoefficients + "eta = 1.3\nroughness = 0.3\n", kLights, true),
                  {27.107234863279125, 7128.8832630966008, 243.37806122489005, 69870.614155344694,
                   470.42598961986795, 108572.11771846135, 391.4764820263926, 89666.875803368923});
    expect_pinned("render smooth boundary",
                  render_pin(kCoefficients + "eta = 1.4\n", kLights, true),
                  {28.125754117195907, 7533.9745794099908, 253.51638479194668, 70522.587770574581,
                   470.78130986750426, 108715.38178526392, 395.08681219167062, 89960.215650018057});
    expect_pinned("render index-matched", render_pin(kCoefficients + "eta = 1.0\n", kLights, true),
                  {29.166848045886589, 7923.5597315735249, 245.93686525817628, 68952.484082457726,
                   474.01936307189078, 109261.200065072, 393.32288467583055, 90046.734797785});
}

// volpath-render-5 is volpath-render-4 but for the absorption of its media's walks (weighted
// where every albedo is at least 0.9, render_absorption): with analog absorption it draws the
// same numbers, so these are volpath-render-4's pins (its agreement with the weighted walk:
// Render.NewerEstimatorsAgreeWithTheLegacyOne).
TEST(WalkGolden, RenderEngineVolpathRender4) {
    expect_pinned("render rough boundary (v4)",
                  render_pin(kCoefficients + "eta = 1.3\nroughness = 0.3\n", kLights, false),
                  {27.855950336647098, 7406.6490545976976, 231.97887627451863, 64399.288648467897,
                   470.68848745189138, 107936.57726582665, 393.50699973253847, 90213.696984040114});
    expect_pinned("render smooth boundary (v4)",
                  render_pin(kCoefficients + "eta = 1.4\n", kLights, false),
                  {28.096889915235696, 7497.3676639305713, 229.50998472510514, 63887.260657715509,
                   475.6970766567951, 108675.44582498923, 393.13344735496986, 90030.489742415259});
    expect_pinned("render index-matched (v4)",
                  render_pin(kCoefficients + "eta = 1.0\n", kLights, false),
                  {28.408467319011226, 7618.883561319185, 234.60399920953105, 65286.672987870283,
                   478.91099537733146, 109458.99530109798, 394.40887916438766, 90353.727664208753});
}

// volpath-render-5's defaults: the pinned medium (albedo 0.95, 0.97, 0.98) walks with weighted
// absorption.
TEST(WalkGolden, RenderEngineVolpathRender5) {
    expect_pinned(
        "render rough boundary (v5)",
        render_pin(kCoefficients + "eta = 1.3\nroughness = 0.3\n", kLights, false, std::nullopt),
        {27.97014198895122, 7451.2615582350882, 230.32031164332454, 64241.195112279049,
         471.84428794045914, 108282.49985762463, 393.15142932853041, 90064.735900840635});
    expect_pinned("render smooth boundary (v5)",
                  render_pin(kCoefficients + "eta = 1.4\n", kLights, false, std::nullopt),
                  {28.053839481561855, 7480.3173980212523, 229.72658859410461, 63956.014011176245,
                   472.52447189954341, 108540.90928203831, 394.01521504742345, 90096.719131332633});
    expect_pinned("render index-matched (v5)",
                  render_pin(kCoefficients + "eta = 1.0\n", kLights, false, std::nullopt),
                  {28.295791636106738, 7574.4269660904647, 235.71566090027196, 65405.938255536159,
                   476.16211871901999, 109182.7097059786, 394.53140262361507, 90287.734681607966});
}

// volpath-render-6's defaults: the hero chosen at the medium's entry by throughput x albedo
// (one number from the stream there), the environment sampled about a surface's normal by
// cos(theta) (its agreement with the old estimators: Render.NewerEstimatorsAgreeWithTheLegacyOne;
// with closed forms: Render's furnace, single-scattering and diffuse-sphere tests).
TEST(WalkGolden, RenderEngineVolpathRender6) {
    expect_pinned("render rough boundary (v6)",
                  render_pin(kCoefficients + "eta = 1.3\nroughness = 0.3\n", kLights, false,
                             std::nullopt, true),
                  {27.805747460520845, 7387.8575108956702, 234.451369146753, 65245.493445825065,
                   472.0116359470772, 108280.93026447114, 393.61408007044338, 90024.986383101903});
    expect_pinned("render smooth boundary (v6)",
                  render_pin(kCoefficients + "eta = 1.4\n", kLights, false, std::nullopt, true),
                  {28.043737496565321, 7477.247000560681, 233.26143068851755, 65337.363309710025,
                   473.2315479619192, 108583.41246994091, 392.39764589655545, 89920.493967366841});
    expect_pinned("render index-matched (v6)",
                  render_pin(kCoefficients + "eta = 1.0\n", kLights, false, std::nullopt, true),
                  {28.244254199450861, 7553.7591880419795, 237.26293554810593, 65581.808404076481,
                   476.77173663734123, 109340.08712605348, 394.36662711691463, 90314.026273336305});
}

// volpath-render-7's defaults: rays from a surface (NEE's shadow rays, the path's rays outside
// media) start at the surface point and skip its triangle (their agreement with
// volpath-render-6's: Render.NewerEstimatorsAgreeWithTheLegacyOne; the shadows of an occluder
// closer than the old offset: Render.ShadowsOfOccludersCloserThanTheSceneEpsilonAreCast and
// Render.AnOccluderCloserThanTheSceneEpsilonShadowsTheSky).
TEST(WalkGolden, RenderEngineVolpathRender7) {
    expect_pinned("render rough boundary (v7)",
                  render_pin(kCoefficients + "eta = 1.3\nroughness = 0.3\n", kLights, false,
                             std::nullopt, true, true),
                  {27.805746958116192, 7387.8573126970332, 234.45164676601183, 65245.594386546341,
                   472.01158788734961, 108280.91604163079, 393.61402775832738, 90024.966224092845});
    expect_pinned(
        "render smooth boundary (v7)",
        render_pin(kCoefficients + "eta = 1.4\n", kLights, false, std::nullopt, true, true),
        {28.043737861942809, 7477.2471399521928, 233.26144206220181, 65337.366440442485,
         473.23153422443789, 108583.40565280149, 392.39764521940276, 89920.494349980174});
    expect_pinned(
        "render index-matched (v7)",
        render_pin(kCoefficients + "eta = 1.0\n", kLights, false, std::nullopt, true, true),
        {28.244254380290815, 7553.7592593833424, 237.26277660244335, 65581.737423565821,
         476.7714144595891, 109339.9867192856, 394.36699735932336, 90314.009776079067});
}

// A same-g medium behind a rough boundary (the scene of the v8 and v9 pins below).
const std::string kSameG =
    "[[materials]]\nname = \"m\"\nsigma_a_per_mm = [0.05, 0.1, 0.2]\n"
    "sigma_s_per_mm = [1.0, 3.0, 8.0]\ng = 0.5\neta = 1.3\nroughness = 0.3\n";

// volpath-render-8's defaults: exit guides at the scattering vertices of media behind rough
// boundaries whose g is the same in all channels (the pins above have per-channel g, so
// volpath-render-8 keeps them); such a medium without the guide draws volpath-render-7's
// numbers (its agreement with the guided one:
// Render.TheExitGuideAgreesWithTheWalkAloneAndLowersItsVariance).
TEST(WalkGolden, RenderEngineVolpathRender8) {
    const std::string& same_g = kSameG;
    expect_pinned("render rough boundary, one g (v7)",
                  render_pin(same_g, kLights, false, std::nullopt, true, true, false),
                  {28.029280635515857, 7472.6594903212317, 232.22387355304994, 64166.360951180985,
                   472.67522948714912, 108274.63625511063, 393.04202599612887, 90050.116245004261});
    expect_pinned("render rough boundary, one g (v8)",
                  render_pin(same_g, kLights, false, std::nullopt, true, true, true, false),
                  {27.917873591930316, 7431.1689303764579, 232.4512732699616, 64544.930307656723,
                   472.08462318861007, 108334.05724742034, 392.78739498342986, 90025.835060199752});
}

// volpath-render-9's defaults: exit guides at the boundary's own vertices too (the entry, an
// internal reflection); without them a same-g rough medium draws volpath-render-8's numbers
// (above; agreement: Render.BoundaryGuidesAgreeWithTheWalkAloneAndLowerTheVarianceOfAThinMedium).
TEST(WalkGolden, RenderEngineVolpathRender9) {
    expect_pinned("render rough boundary, one g (v9)",
                  render_pin(kSameG, kLights, false, std::nullopt, true, true, true, true),
                  {27.897791076901566, 7423.3078059643785, 231.31763060594824, 64453.843216489928,
                   472.14564069093694, 108416.05445036953, 392.83213495170008, 90011.528211538753});
}

// volpath-render-10's defaults: guides at the floor's vertices straight after the way out of the
// sphere (the floor lies 0.1 mm under it, lit by the sphere light through it); without them a
// same-g rough medium draws volpath-render-9's numbers (above; agreement:
// Render.DiffuseGuidesAgreeWithTheWalkAloneAndLowerTheVarianceOfACausticSeenThroughIt).
TEST(WalkGolden, RenderEngineVolpathRender10) {
    expect_pinned("render rough boundary, one g (v10)",
                  render_pin(kSameG, kLights, false, std::nullopt, true, true, true, true, true),
                  {27.897791076901566, 7423.3078059643785, 231.31763060594824, 64453.843216489928,
                   472.20654194532597, 108329.34933220572, 392.75731782558836, 89988.235652269519});
}

// volpath-render-11's defaults: a wide lobe beside each narrow one of every exit guide; without
// it, volpath-render-10's numbers (above; agreement: the exit guide's and the puddle's tests).
TEST(WalkGolden, RenderEngineVolpathRender11) {
    ASSERT_STREQ(render_engine_version(), "volpath-render-11");
    expect_pinned(
        "render rough boundary, one g (v11)",
        render_pin(kSameG, kLights, false, std::nullopt, true, true, true, true, true, true),
        {27.863862059533044, 7409.6005739375796, 231.93037445713438, 64477.168940364318,
         471.25849321356139, 108116.30715266379, 392.92945443372969, 90021.044284644886});
}

}  // namespace
}  // namespace ssslab::volpath

namespace ssslab::mcml {
namespace {

// MCML's default engine on the van de Hulst slab of tests/data (tau = 2, albedo 0.9, g = 0.75),
// full and profile tallies, 20000 photons in 32 batches on two threads: the means and the
// batch standard errors, as MCML's own driver produced them before the batch loop moved onto
// core/batch_runner (pinned from a build of that code; the shared driver reproduced them to the
// bit).
TEST(WalkGolden, McmlDefaultEngineMcmlDefault3) {
    ASSERT_STREQ(engine_version(), "mcml-default-3");
    const RunSpec run = read_mci(ssslab::testing::data_path("mcml-1.2.2/a_vdh.mci")).runs[0];
    const std::vector<std::vector<double>> means = {
        {0.097419569893089988, 6.5044462752637759, 0.65921693448381724, 328.17131192366924,
         0.22872696807700713, 221.2895804925034, 0.86866593806076864, 853.57535288559495,
         3.1459705894853167, 248.01668066018047},
        {2.9999999999999991, 276.68499046961335}};
    const std::vector<std::vector<double>> ses = {
        {0.022860825260520561, 0.043003496061698829, 0.0071516505416669169, 0.024423378958213809,
         0.036285922027681189},
        {0.020048470311154341}};
    for (int mode = 0; mode < 2; ++mode) {
        EngineOptions o;
        o.seed = 7;
        o.stream = 3;
        o.threads = 2;
        o.mode = mode == 0 ? TallyMode::kFull : TallyMode::kProfile;
        o.budget.samples = 20000;
        const RunResult r = run_default(run, o);
        EXPECT_EQ(r.photons, 20000u);
        EXPECT_EQ(r.batches, 32u);
        EXPECT_EQ(r.events, 61216u);
        const std::vector<double> m = volpath::fold(r.values, 1024);
        volpath::expect_pinned(mode == 0 ? "MCML full" : "MCML profile", m,
                               means[static_cast<std::size_t>(mode)]);
        std::vector<double> se;
        for (std::size_t b = 0; b < r.se.size(); b += 1024) {
            double sum = 0;
            for (std::size_t i = b; i < std::min(r.se.size(), b + 1024); ++i) sum += r.se[i];
            se.push_back(sum);
        }
        volpath::expect_pinned(mode == 0 ? "MCML full (se)" : "MCML profile (se)", se,
                               ses[static_cast<std::size_t>(mode)]);
    }
}

}  // namespace
}  // namespace ssslab::mcml
