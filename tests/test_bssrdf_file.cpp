// The .bssrdf reader [Bitterli13 §A.2]: Listing A.2 read as printed, every construct of the
// appendix, and each kind of bad file refused at its line.
#include "approx/bssrdf_file.h"
#include "core/error.h"
#include "tests/testing.h"

#include <gtest/gtest.h>

using namespace ssslab;
using approx::BssrdfParameter;

namespace {

// The error a bad file raises: its line and message.
InputError error_of(const std::string& text) {
    return ssslab::testing::input_error_of([&] { approx::parse_bssrdf(text, "bad.bssrdf"); }, text);
}

const char* const kShader =
    "::begin shader\nvec3 Bssrdf(vec3 Xi, vec3 Wi, vec3 Xo, vec3 Wo) "
    "{ return vec3(1.0); }\n::end shader\n";

}  // namespace

TEST(BssrdfFile, ListingA2IsReadAsPrinted) {
    const approx::BssrdfFile f =
        approx::read_bssrdf(ssslab::testing::source_path("experiments/bssrdf/dipole.bssrdf"));
    EXPECT_TRUE(f.radial);
    EXPECT_TRUE(f.no_wi);
    EXPECT_TRUE(f.no_wo);
    ASSERT_EQ(f.parameters.size(), 1u);
    const BssrdfParameter& m = f.parameters[0];
    EXPECT_EQ(m.type, BssrdfParameter::Type::kFloat);
    EXPECT_EQ(m.name, "Multiplier");
    EXPECT_EQ(m.min, 0.0);
    EXPECT_EQ(m.max, 10.0);
    EXPECT_EQ(m.fallback[0], 1.0);
    EXPECT_EQ(m.line, 4);
    ASSERT_TRUE(f.initializer && f.diffuse_reflectance && f.shader);
    // Each section's first line is the one after its ::begin, for the GLSL compiler's messages.
    EXPECT_EQ(f.initializer->first_line, 8);
    EXPECT_EQ(f.diffuse_reflectance->first_line, 27);
    EXPECT_EQ(f.shader->first_line, 36);
    EXPECT_NE(f.initializer->code.find("void init() {"), std::string::npos);
    EXPECT_NE(f.diffuse_reflectance->code.find("vec3 DiffuseReflectance(vec3 AlphaPrime)"),
              std::string::npos);
    EXPECT_NE(f.shader->code.find("return Multiplier/(4.0*PI)*AlphaPrime*(FluenceR + FluenceV);"),
              std::string::npos);
    EXPECT_EQ(f.shader->code.find("::end"), std::string::npos);
    EXPECT_TRUE(f.ignored_sections.empty());
}

TEST(BssrdfFile, EveryConstructOfTheAppendix) {
    // Leading blank lines, CRLF endings, sections in any order, an unknown section ignored,
    // every parameter type and bool spelling, the optional sections left out.
    const std::string text = "\r\n\r\nanalytic\r\n\r\n" + std::string(kShader) +
                             "::begin notes\nanything at all\n::end notes\n"
                             "::begin parameters\n"
                             "float Scale -1 2.5e1 0.5\n"
                             "\n"
                             "bool UseSingle true\n"
                             "bool Flip 0\n"
                             "bool On 1\n"
                             "bool Off false\n"
                             "color Tint 0.25 0.5 1\n"
                             "::end parameters\n";
    const approx::BssrdfFile f = approx::parse_bssrdf(text, "ok.bssrdf");
    EXPECT_FALSE(f.radial || f.no_wi || f.no_wo);
    EXPECT_FALSE(f.initializer || f.diffuse_reflectance);
    ASSERT_TRUE(f.shader);
    EXPECT_EQ(f.shader->first_line, 6);
    ASSERT_EQ(f.ignored_sections.size(), 1u);
    EXPECT_EQ(f.ignored_sections[0], "notes");
    ASSERT_EQ(f.parameters.size(), 6u);
    const BssrdfParameter* s = f.find_parameter("Scale");
    ASSERT_NE(s, nullptr);
    EXPECT_EQ(s->min, -1.0);
    EXPECT_EQ(s->max, 25.0);
    EXPECT_EQ(s->fallback[0], 0.5);
    EXPECT_EQ(f.find_parameter("UseSingle")->fallback[0], 1.0);
    EXPECT_EQ(f.find_parameter("Flip")->fallback[0], 0.0);
    EXPECT_EQ(f.find_parameter("On")->fallback[0], 1.0);
    EXPECT_EQ(f.find_parameter("Off")->fallback[0], 0.0);
    const BssrdfParameter* t = f.find_parameter("Tint");
    EXPECT_EQ(t->type, BssrdfParameter::Type::kColor);
    EXPECT_EQ(t->fallback, (std::array<double, 3>{0.25, 0.5, 1.0}));
    EXPECT_EQ(f.find_parameter("Nope"), nullptr);
}

TEST(BssrdfFile, BadFilesAreRefusedAtTheirLine) {
    const std::string shader = kShader;
    struct Case {
        std::string text;
        int line;
        std::string says;
    } cases[] = {
        {"", 1, "empty file"},
        {"analytic radial smooth\n" + shader, 1, "unknown attribute 'smooth'"},
        {"radial no_wi\n" + shader, 1, "'analytic' is mandatory"},
        {"::begin shader\n::end shader\n", 1, "first line must list the attributes"},
        {"analytic\nvec3 x;\n" + shader, 2, "text outside a section"},
        {"analytic\n::begin\n::end\n" + shader, 2, "takes one section name"},
        {"analytic\n::begin a b\n::end a\n" + shader, 2, "takes one section name"},
        {"analytic\n::begin initializer\n::begin shader\n::end shader\n", 3,
         "'::begin' inside section 'initializer'"},
        {"analytic\n::begin initializer\nvoid init() {}\n::end shader\n" + shader, 4,
         "expected '::end initializer'"},
        {"analytic\n" + shader + "::end shader\n", 5, "'::end' without a '::begin'"},
        {"analytic\n" + shader + "::begin initializer\nvoid init() {}\n", 5,
         "section 'initializer' has no '::end initializer'"},
        {"analytic\n" + shader + shader, 5, "section 'shader' is given twice"},
        {"analytic\n::begin parameters\n::end parameters\n::begin parameters\n::end "
         "parameters\n" +
             shader,
         4, "section 'parameters' is given twice"},
        {"analytic\n::begin parameters\nint N 0 1 0\n::end parameters\n" + shader, 3,
         "unknown parameter type 'int'"},
        {"analytic\n::begin parameters\nfloat K 0 1\n::end parameters\n" + shader, 3,
         "declared as 'float NAME MIN MAX DEFAULT'"},
        {"analytic\n::begin parameters\ncolor C 1 1\n::end parameters\n" + shader, 3,
         "declared as 'color NAME R G B'"},
        {"analytic\n::begin parameters\nbool B\n::end parameters\n" + shader, 3,
         "declared as 'bool NAME DEFAULT'"},
        {"analytic\n::begin parameters\nfloat K 0 one 0.5\n::end parameters\n" + shader, 3,
         "'one' is not a finite number"},
        {"analytic\n::begin parameters\nfloat K 0 1 nan\n::end parameters\n" + shader, 3,
         "'nan' is not a finite number"},
        {"analytic\n::begin parameters\nfloat K 0 1 1.5\n::end parameters\n" + shader, 3,
         "the default 1.5 is outside [0, 1]"},
        {"analytic\n::begin parameters\nfloat K 2 1 1.5\n::end parameters\n" + shader, 3,
         "the minimum 2 exceeds the maximum 1"},
        {"analytic\n::begin parameters\nbool B yes\n::end parameters\n" + shader, 3,
         "a bool's default is true, false, 1 or 0"},
        {"analytic\n::begin parameters\nfloat K 0 1 0\ncolor K 1 1 1\n::end parameters\n" + shader,
         4, "parameter 'K' is declared twice"},
        {"analytic\n::begin parameters\nfloat IOR 1 2 1.3\n::end parameters\n" + shader, 3,
         "'IOR' is defined by the application"},
        {"analytic\n::begin parameters\nfloat 2x 0 1 0\n::end parameters\n" + shader, 3,
         "'2x' is not a GLSL identifier"},
        {"analytic radial\n::begin initializer\nvoid init() {}\n::end initializer\n", 0,
         "no 'shader' section"},
    };
    for (const Case& c : cases) {
        const InputError e = error_of(c.text);
        EXPECT_EQ(e.where().file, "bad.bssrdf");
        EXPECT_EQ(e.where().line, c.line) << c.text << "\n" << e.what();
        EXPECT_NE(std::string(e.what()).find(c.says), std::string::npos)
            << "expected '" << c.says << "' in: " << e.what();
    }
}

TEST(BssrdfFile, AnUnreadableFileIsAnInputError) {
    try {
        approx::read_bssrdf("/nonexistent/model.bssrdf");
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_EQ(e.where().file, "/nonexistent/model.bssrdf");
        EXPECT_NE(std::string(e.what()).find("cannot read"), std::string::npos);
    }
}
