// LayeredImage: the layer API, OpenEXR round trips (bit-exact floats, metadata), reading files
// written independently through the OpenEXR API (half, tiled, multi-part, offset windows), layer
// grouping by channel name, errors on bad files, and the sRGB PNG preview.
#include "core/error.h"
#include "core/film_image.h"
#include "testing.h"

#include <Imath/half.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfMultiPartOutputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfOutputPart.h>
#include <OpenEXR/ImfPartType.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/ImfTiledOutputFile.h>
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <string>
#include <vector>

namespace ssslab {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

std::uint32_t bits(float f) {
    return std::bit_cast<std::uint32_t>(f);
}

// Values that a lossy or converting path would change: infinities, denormals, signed zero,
// extremes, values that are not representable in half precision.
std::vector<float> special_values() {
    const float inf = std::numeric_limits<float>::infinity();
    return {0.0f,
            -0.0f,
            1.0f,
            -1.0f,
            inf,
            -inf,
            std::numeric_limits<float>::denorm_min(),
            -std::numeric_limits<float>::denorm_min(),
            1.17549421e-38f,  // largest denormal
            std::numeric_limits<float>::min(),
            std::numeric_limits<float>::max(),
            std::numeric_limits<float>::lowest(),
            0.1f,
            -123456.789f,
            3.14159274f,
            1e-30f,
            65505.0f};
}

// Deterministic, varied values for pixel (x, y), channel c of layer l; special values mixed in.
float value(int l, int x, int y, int c) {
    const auto sv = special_values();
    const unsigned h = static_cast<unsigned>(x) * 73856093u ^ static_cast<unsigned>(y) * 19349663u ^
                       static_cast<unsigned>(c) * 83492791u ^
                       static_cast<unsigned>(l) * 2654435761u;
    if (h % 5 == 0) return sv[h % sv.size()];
    return (static_cast<float>(h % 100003) - 50000.0f) * 1.37e-3f;
}

void expect_same_bits(const ImageLayer& a, const ImageLayer& b) {
    ASSERT_EQ(a.channel_names(), b.channel_names()) << a.name();
    ASSERT_EQ(a.width(), b.width());
    ASSERT_EQ(a.height(), b.height());
    const auto pa = a.pixels(), pb = b.pixels();
    ASSERT_EQ(pa.size(), pb.size());
    size_t mismatches = 0;
    for (size_t i = 0; i < pa.size(); ++i) {
        if (std::isnan(pa[i]) && std::isnan(pb[i])) continue;  // payload not required
        if (bits(pa[i]) != bits(pb[i]) && ++mismatches <= 5)
            ADD_FAILURE() << "layer '" << a.name() << "' value " << i << ": " << pa[i] << " vs "
                          << pb[i];
    }
    EXPECT_EQ(mismatches, 0u);
}

LayeredImage make_image(int w, int h) {
    LayeredImage img(w, h);
    // Added out of name order: read_exr returns them sorted.
    const std::vector<std::pair<std::string, std::vector<std::string>>> spec = {
        {"radiance", {"R", "G", "B"}},
        {"subsurface", {"R", "G", "B"}},
        {"specular", {"R", "G", "B"}},
        {"stderr", {"R", "G", "B"}},
        {"depth", {"Z"}},
        {"normal", {"X", "Y", "Z"}},
        {"", {"R", "G", "B"}},
        {"diffuse.direct", {"Y"}}};
    for (size_t l = 0; l < spec.size(); ++l) {
        ImageLayer& layer = img.add_layer(spec[l].first, spec[l].second);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                for (int c = 0; c < layer.channels(); ++c)
                    layer.at(x, y, c) = value(static_cast<int>(l), x, y, c);
    }
    img.layer("radiance").at(0, 0, 1) = std::numeric_limits<float>::quiet_NaN();
    return img;
}

std::vector<std::string> layer_names(const LayeredImage& img) {
    std::vector<std::string> names;
    for (const auto& l : img.layers()) names.push_back(l.name());
    return names;
}

// Throws `E` and its message names `path`.
template <class E, class F>
void expect_error_naming(F&& f, const std::string& path, const std::string& what = {}) {
    try {
        f();
        ADD_FAILURE() << "no exception for " << path;
    } catch (const E& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find(path), std::string::npos) << msg;
        if (!what.empty()) {
            EXPECT_NE(msg.find(what), std::string::npos) << msg;
        }
    }
}

// --- the layer API ---------------------------------------------------------------------------

TEST(LayeredImage, AddsAndFindsLayers) {
    LayeredImage img(4, 3);
    ImageLayer& rad = img.add_layer("radiance", 3);
    ImageLayer& depth = img.add_layer("depth", 1);
    for (int i = 0; i < 50; ++i) img.add_layer("extra" + std::to_string(i), 1);
    rad.at(3, 2, 2) = 7.0f;  // references stay valid after more layers are added
    depth.at(1, 0) = 2.0f;
    EXPECT_EQ(img.layer("radiance").channel_names(), (std::vector<std::string>{"R", "G", "B"}));
    EXPECT_EQ(img.layer("depth").channel_names(), (std::vector<std::string>{"Y"}));
    EXPECT_EQ(img.layer("radiance").pixels()[(2 * 4 + 3) * 3 + 2], 7.0f);
    EXPECT_EQ(img.layer("depth").pixels()[1], 2.0f);
    EXPECT_EQ(img.layer("radiance").exr_channel_name(1), "radiance.G");
    EXPECT_TRUE(img.has_layer("depth"));
    EXPECT_FALSE(img.has_layer("Depth"));
    EXPECT_EQ(img.layers().size(), 52u);
    EXPECT_EQ(img.layers().front().name(), "radiance");  // insertion order

    std::vector<float> px(4 * 3 * 3, 1.5f);
    const ImageLayer& given = img.add_layer("", 3, px);
    EXPECT_EQ(given.exr_channel_name(0), "R");
    EXPECT_EQ(given.at(2, 1, 1), 1.5f);
}

TEST(LayeredImage, RejectsMisuse) {
    EXPECT_THROW(LayeredImage(0, 3), std::invalid_argument);
    EXPECT_THROW(LayeredImage(3, -1), std::invalid_argument);
    LayeredImage img(4, 3);
    img.add_layer("radiance", 3);
    img.add_layer("depth", 1);
    try {
        (void)img.layer("radience");
        ADD_FAILURE();
    } catch (const std::invalid_argument& e) {
        // Names the unknown layer and lists those that exist.
        const std::string msg = e.what();
        EXPECT_NE(msg.find("'radience'"), std::string::npos) << msg;
        EXPECT_NE(msg.find("'radiance', 'depth'"), std::string::npos) << msg;
    }
    EXPECT_THROW(img.add_layer("radiance", 1), std::invalid_argument);  // duplicate
    EXPECT_THROW(img.add_layer("two", 2), std::invalid_argument);       // no default names
    EXPECT_THROW(img.add_layer("zero", 0), std::invalid_argument);
    EXPECT_THROW(img.add_layer("wrong", 3, std::vector<float>(4 * 3 * 3 - 1)),
                 std::invalid_argument);
    EXPECT_THROW(img.add_layer("wrong", 1, std::vector<float>(4 * 3 * 3)), std::invalid_argument);
    EXPECT_THROW(img.add_layer("a", std::vector<std::string>{"R", "R"}), std::invalid_argument);
    EXPECT_THROW(img.add_layer("a", std::vector<std::string>{"R."}), std::invalid_argument);
    EXPECT_THROW(img.add_layer("a", std::vector<std::string>{""}), std::invalid_argument);
    EXPECT_THROW(img.add_layer("a", std::vector<std::string>{}), std::invalid_argument);
    EXPECT_THROW(img.add_layer(".a", 1), std::invalid_argument);
    EXPECT_THROW(img.add_layer("a.", 1), std::invalid_argument);
    EXPECT_THROW(img.add_layer("a..b", 1), std::invalid_argument);
    EXPECT_THROW(img.add_layer(std::string(300, 'x'), 1), std::invalid_argument);
    EXPECT_EQ(img.layers().size(), 2u);  // nothing was added by the failed calls

    const LayeredImage empty(2, 2);
    TempDir dir;
    EXPECT_THROW(write_exr(empty, (dir / "empty.exr").string()), std::invalid_argument);
    EXPECT_TRUE(dir.files().empty());
}

// --- OpenEXR round trips -----------------------------------------------------------------------

class ExrRoundTrip : public ::testing::TestWithParam<std::pair<int, int>> {};

TEST_P(ExrRoundTrip, IsBitExact) {
    const auto [w, h] = GetParam();
    const LayeredImage img = make_image(w, h);
    TempDir dir;
    const std::string path = (dir / "film.exr").string();
    write_exr(img, path);
    EXPECT_EQ(dir.files(), (std::vector<std::string>{"film.exr"}));  // no temporary left
    const LayeredImage back = read_exr(path);
    EXPECT_EQ(back.width(), w);
    EXPECT_EQ(back.height(), h);
    // Sorted by name, the default layer first.
    EXPECT_EQ(layer_names(back),
              (std::vector<std::string>{"", "depth", "diffuse.direct", "normal", "radiance",
                                        "specular", "stderr", "subsurface"}));
    for (const auto& l : img.layers()) expect_same_bits(l, back.layer(l.name()));
    EXPECT_TRUE(std::isnan(back.layer("radiance").at(0, 0, 1)));
    EXPECT_TRUE(back.metadata().empty());
}

INSTANTIATE_TEST_SUITE_P(Sizes, ExrRoundTrip,
                         ::testing::Values(std::pair{1, 1}, std::pair{1000, 3}, std::pair{3, 1000},
                                           std::pair{37, 19}),
                         [](const auto& param_info) {
                             return std::to_string(param_info.param.first) + "x" +
                                    std::to_string(param_info.param.second);
                         });

TEST(Exr, RoundTripsMetadata) {
    LayeredImage img(2, 2);
    img.add_layer("radiance", 3);
    img.metadata()["ssslab.spp"] = "4096";
    img.metadata()["ssslab.seed"] = "18446744073709551615";
    img.metadata()["ssslab.config"] = "[scene]\nunit = \"mm\"\n# ünïcode, tabs\tand \"quotes\"\n\n";
    img.metadata()["ssslab.empty"] = "";
    img.metadata()["owner"] = "ssslab tests";  // a standard string attribute is fine
    TempDir dir;
    const std::string path = (dir / "meta.exr").string();
    write_exr(img, path);
    const LayeredImage back = read_exr(path);
    EXPECT_EQ(back.metadata(), img.metadata());

    // Overwriting an existing file replaces it.
    img.metadata().erase("ssslab.empty");
    write_exr(img, path);
    EXPECT_EQ(read_exr(path).metadata(), img.metadata());
    EXPECT_EQ(dir.files(), (std::vector<std::string>{"meta.exr"}));
}

TEST(Exr, RejectsMetadataKeysOfStandardAttributes) {
    TempDir dir;
    for (const std::string key : {"compression", "dataWindow", "channels", "type", "name", ""}) {
        LayeredImage img(2, 2);
        img.add_layer("radiance", 3);
        img.metadata()[key] = "x";
        EXPECT_THROW(write_exr(img, (dir / "bad.exr").string()), std::invalid_argument) << key;
    }
    EXPECT_TRUE(dir.files().empty());
}

// --- files written independently through the OpenEXR API --------------------------------------

// Values exactly representable in half, including its denormals, extremes and infinities.
std::vector<half> half_values() {
    std::vector<half> v;
    for (float f : {0.0f, -0.0f, 0.5f, -2.25f, 1.0f / 3.0f, 65504.0f, -65504.0f,
                    5.9604645e-08f /* smallest half denormal */, 6.097555e-05f, 1000.0f})
        v.emplace_back(f);
    v.push_back(half::posInf());
    v.push_back(half::negInf());
    return v;
}

half half_value(int x, int y, int c) {
    const auto hv = half_values();
    return hv[static_cast<size_t>(x * 7 + y * 3 + c * 5) % hv.size()];
}

// A scanline (or tiled) file with HALF channels R, G, B (default layer), diffuse.{R,G,B} and
// depth.Z, whose pixel (x, y) of channel k holds half_value(x, y, k).
void write_half_file(const std::string& path, int w, int h, bool tiled) {
    const std::vector<std::string> names = {"R",         "G",         "B",      "diffuse.R",
                                            "diffuse.G", "diffuse.B", "depth.Z"};
    Imf::Header header(w, h);
    header.compression() = tiled ? Imf::PIZ_COMPRESSION : Imf::ZIP_COMPRESSION;
    for (const auto& n : names) header.channels().insert(n, Imf::Channel(Imf::HALF));
    if (tiled) header.setTileDescription(Imf::TileDescription(16, 8, Imf::ONE_LEVEL));
    std::vector<std::vector<half>> data(names.size(),
                                        std::vector<half>(static_cast<size_t>(w) * h));
    Imf::FrameBuffer fb;
    for (size_t k = 0; k < names.size(); ++k) {
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                data[k][static_cast<size_t>(y) * w + x] = half_value(x, y, static_cast<int>(k));
        fb.insert(names[k], Imf::Slice(Imf::HALF, reinterpret_cast<char*>(data[k].data()),
                                       sizeof(half), sizeof(half) * static_cast<size_t>(w)));
    }
    if (tiled) {
        Imf::TiledOutputFile out(path.c_str(), header);
        out.setFrameBuffer(fb);
        out.writeTiles(0, out.numXTiles() - 1, 0, out.numYTiles() - 1);
    } else {
        Imf::OutputFile out(path.c_str(), header);
        out.setFrameBuffer(fb);
        out.writePixels(h);
    }
}

void expect_half_file(const LayeredImage& img, int w, int h) {
    ASSERT_EQ(img.width(), w);
    ASSERT_EQ(img.height(), h);
    ASSERT_EQ(layer_names(img), (std::vector<std::string>{"", "depth", "diffuse"}));
    const ImageLayer& def = img.layer("");
    const ImageLayer& diffuse = img.layer("diffuse");
    const ImageLayer& depth = img.layer("depth");
    EXPECT_EQ(def.channel_names(), (std::vector<std::string>{"R", "G", "B"}));
    EXPECT_EQ(depth.channel_names(), (std::vector<std::string>{"Z"}));
    int bad = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            for (int c = 0; c < 3; ++c) {
                bad += bits(def.at(x, y, c)) != bits(float(half_value(x, y, c)));
                bad += bits(diffuse.at(x, y, c)) != bits(float(half_value(x, y, 3 + c)));
            }
            bad += bits(depth.at(x, y)) != bits(float(half_value(x, y, 6)));
        }
    EXPECT_EQ(bad, 0);
}

TEST(Exr, ReadsHalfScanlineFileFromOpenExr) {
    TempDir dir;
    const std::string path = (dir / "half.exr").string();
    write_half_file(path, 45, 21, false);
    expect_half_file(read_exr(path), 45, 21);
}

TEST(Exr, ReadsHalfTiledFileFromOpenExr) {
    TempDir dir;
    const std::string path = (dir / "tiled.exr").string();
    write_half_file(path, 45, 21, true);  // partial tiles on the right and bottom edges
    expect_half_file(read_exr(path), 45, 21);
}

TEST(Exr, ReadsDisplayWindowWithOffsetDataWindows) {
    // Display window [10, 17] x [-3, 2]; part 0's data window lies inside it, part 1's sticks out
    // on the left and below (that part is cropped), both in a multi-part file.
    const Imath::Box2i disp(Imath::V2i(10, -3), Imath::V2i(17, 2));
    const Imath::Box2i dw0(Imath::V2i(12, -2), Imath::V2i(15, 0));
    const Imath::Box2i dw1(Imath::V2i(5, 1), Imath::V2i(11, 6));
    Imf::Header h0(disp, dw0), h1(disp, dw1);
    h0.channels().insert("a.R", Imf::Channel(Imf::FLOAT));
    h0.channels().insert("a.G", Imf::Channel(Imf::FLOAT));
    h0.channels().insert("a.B", Imf::Channel(Imf::FLOAT));
    h1.channels().insert("b.Y", Imf::Channel(Imf::HALF));
    h0.setName("beauty");
    h1.setName("aux");
    h0.setType(Imf::SCANLINEIMAGE);
    h1.setType(Imf::SCANLINEIMAGE);
    h0.insert("ssslab.note", Imf::StringAttribute("part0"));
    const auto f0 = [](int x, int y, int c) { return static_cast<float>(x * 100 + y * 10 + c); };
    const auto f1 = [](int x, int y) { return half(static_cast<float>(x - y)); };
    std::vector<float> d0;
    for (int y = dw0.min.y; y <= dw0.max.y; ++y)
        for (int x = dw0.min.x; x <= dw0.max.x; ++x)
            for (int c = 0; c < 3; ++c) d0.push_back(f0(x, y, c));
    std::vector<half> d1;
    for (int y = dw1.min.y; y <= dw1.max.y; ++y)
        for (int x = dw1.min.x; x <= dw1.max.x; ++x) d1.push_back(f1(x, y));
    TempDir dir;
    const std::string path = (dir / "windows.exr").string();
    {
        Imf::MultiPartOutputFile out(path.c_str(), std::vector<Imf::Header>{h0, h1}.data(), 2);
        Imf::OutputPart p0(out, 0), p1(out, 1);
        Imf::FrameBuffer fb0, fb1;
        for (int c = 0; c < 3; ++c)
            fb0.insert(std::string("a.") + "RGB"[c],
                       Imf::Slice::Make(Imf::FLOAT, d0.data() + c, dw0, 3 * sizeof(float),
                                        3 * sizeof(float) * 4));
        fb1.insert("b.Y",
                   Imf::Slice::Make(Imf::HALF, d1.data(), dw1, sizeof(half), sizeof(half) * 7));
        p0.setFrameBuffer(fb0);
        p0.writePixels(dw0.max.y - dw0.min.y + 1);
        p1.setFrameBuffer(fb1);
        p1.writePixels(dw1.max.y - dw1.min.y + 1);
    }
    const LayeredImage img = read_exr(path);
    ASSERT_EQ(img.width(), 8);
    ASSERT_EQ(img.height(), 6);
    ASSERT_EQ(layer_names(img), (std::vector<std::string>{"a", "b"}));
    EXPECT_EQ(img.metadata().at("ssslab.note"), "part0");
    EXPECT_EQ(img.metadata().count("name"), 0u);
    const auto inside = [](const Imath::Box2i& b, int x, int y) {
        return x >= b.min.x && x <= b.max.x && y >= b.min.y && y <= b.max.y;
    };
    for (int y = disp.min.y; y <= disp.max.y; ++y)
        for (int x = disp.min.x; x <= disp.max.x; ++x) {
            const int px = x - disp.min.x, py = y - disp.min.y;  // (0, 0) is the top-left
            for (int c = 0; c < 3; ++c)
                EXPECT_EQ(img.layer("a").at(px, py, c), inside(dw0, x, y) ? f0(x, y, c) : 0.0f)
                    << x << "," << y;
            EXPECT_EQ(img.layer("b").at(px, py), inside(dw1, x, y) ? float(f1(x, y)) : 0.0f)
                << x << "," << y;
        }
}

TEST(Exr, GroupsChannelsIntoLayersByName) {
    const std::vector<std::string> names = {"A",
                                            "B",
                                            "G",
                                            "R",
                                            "mask",
                                            "depth.Z",
                                            "normal.Z",
                                            "normal.X",
                                            "normal.Y",
                                            "diffuse.direct.B",
                                            "diffuse.direct.G",
                                            "diffuse.direct.R",
                                            "aov.beta",
                                            "aov.alpha"};
    const int w = 3, h = 2;
    Imf::Header header(w, h);
    for (const auto& n : names) header.channels().insert(n, Imf::Channel(Imf::FLOAT));
    std::vector<std::vector<float>> data(names.size());
    Imf::FrameBuffer fb;
    for (size_t k = 0; k < names.size(); ++k) {
        data[k].assign(static_cast<size_t>(w) * h, static_cast<float>(k));
        fb.insert(names[k], Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(data[k].data()),
                                       sizeof(float), sizeof(float) * w));
    }
    TempDir dir;
    const std::string path = (dir / "groups.exr").string();
    {
        Imf::OutputFile out(path.c_str(), header);
        out.setFrameBuffer(fb);
        out.writePixels(h);
    }
    const LayeredImage img = read_exr(path);
    EXPECT_EQ(layer_names(img),
              (std::vector<std::string>{"", "aov", "depth", "diffuse.direct", "normal"}));
    using N = std::vector<std::string>;
    EXPECT_EQ(img.layer("").channel_names(), (N{"R", "G", "B", "A", "mask"}));
    EXPECT_EQ(img.layer("aov").channel_names(), (N{"alpha", "beta"}));
    EXPECT_EQ(img.layer("depth").channel_names(), (N{"Z"}));
    EXPECT_EQ(img.layer("diffuse.direct").channel_names(), (N{"R", "G", "B"}));
    EXPECT_EQ(img.layer("normal").channel_names(), (N{"X", "Y", "Z"}));
    // Each channel's values came along with it.
    for (const auto& l : img.layers())
        for (int c = 0; c < l.channels(); ++c) {
            const auto k =
                std::find(names.begin(), names.end(), l.exr_channel_name(c)) - names.begin();
            EXPECT_EQ(l.at(w - 1, h - 1, c), static_cast<float>(k)) << l.exr_channel_name(c);
        }
}

// --- errors ------------------------------------------------------------------------------------

TEST(Exr, MissingFileIsAnInputErrorNamingIt) {
    TempDir dir;
    const std::string path = (dir / "nope.exr").string();
    expect_error_naming<InputError>([&] { (void)read_exr(path); }, path, "no such file");
    try {
        (void)read_exr(path);
    } catch (const InputError& e) {
        EXPECT_EQ(e.where().file, path);
    }
    expect_error_naming<InputError>([&] { (void)read_exr(dir.path().string()); },
                                    dir.path().string(), "directory");
}

TEST(Exr, TextFileIsAnInputErrorNamingIt) {
    TempDir dir;
    const std::string text = dir.write("notes.exr", "this is not an image\n").string();
    expect_error_naming<InputError>([&] { (void)read_exr(text); }, text, "not an OpenEXR file");
    const std::string empty = dir.write("empty.exr", "").string();
    expect_error_naming<InputError>([&] { (void)read_exr(empty); }, empty, "not an OpenEXR");
    // The magic number alone is not enough.
    const std::string magic = dir.write("magic.exr", std::string("\x76\x2f\x31\x01", 4)).string();
    expect_error_naming<InputError>([&] { (void)read_exr(magic); }, magic);
}

TEST(Exr, TruncatedFileIsAnInputErrorNamingIt) {
    TempDir dir;
    const std::string good = (dir / "good.exr").string();
    write_exr(make_image(64, 40), good);
    const std::string bytes = testing::read_text(good);
    ASSERT_GT(bytes.size(), 1000u);
    // Cut inside the header, inside the offset table, inside the pixel data, and one byte short.
    for (size_t len : {size_t{8}, size_t{100}, size_t{400}, bytes.size() / 2, bytes.size() - 200,
                       bytes.size() - 1}) {
        const std::string path =
            dir.write("cut" + std::to_string(len) + ".exr", bytes.substr(0, len)).string();
        expect_error_naming<InputError>([&] { (void)read_exr(path); }, path);
    }
}

TEST(Exr, CorruptFilesNeverCrash) {
    // Every byte in turn overwritten, across the header, the offset table and the data: an
    // InputError or a successful read (a changed byte inside compressed data may still decode),
    // never a crash or another exception.
    TempDir dir;
    const std::string good = (dir / "good.exr").string();
    LayeredImage img = make_image(3, 2);  // eight layers of varied values
    img.metadata()["ssslab.seed"] = "1";
    write_exr(img, good);
    const std::string bytes = testing::read_text(good);
    // The values of the data and display windows are skipped: changed, they make a valid file of
    // a different (possibly gigabyte-sized) image rather than a corrupt one.
    std::vector<bool> skip(bytes.size(), false);
    for (const std::string attr : {"dataWindow", "displayWindow"}) {
        const size_t at = bytes.find(attr + std::string("\0box2i\0", 7));
        ASSERT_NE(at, std::string::npos) << attr;
        const size_t value = at + attr.size() + 7 + 4;  // after name, type and size
        for (size_t i = value; i < value + 16; ++i) skip[i] = true;
    }
    int errors = 0, reads = 0;
    for (size_t pos = 4; pos < bytes.size(); ++pos) {
        if (skip[pos]) continue;
        std::string bad = bytes;
        bad[pos] = static_cast<char>(bad[pos] ^ 0x5a);
        // A new name each time: truncating a just-written file makes ext4 flush it (slow).
        const std::string path = dir.write("corrupt" + std::to_string(pos) + ".exr", bad).string();
        try {
            (void)read_exr(path);
            ++reads;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
            ++errors;
        }
        fs::remove(path);
    }
    EXPECT_GT(errors, 0);
    std::cout << "corrupt files: " << errors << " rejected, " << reads << " read\n";
}

TEST(Exr, WriteIntoMissingDirectoryFailsAndLeavesNothing) {
    TempDir dir;
    LayeredImage img(5, 4);
    img.add_layer("radiance", 3);
    const fs::path missing = dir / "no_such_dir";
    const std::string path = (missing / "film.exr").string();
    expect_error_naming<IoError>([&] { write_exr(img, path); }, path);
    EXPECT_FALSE(fs::exists(missing));
    EXPECT_TRUE(dir.files().empty());
    EXPECT_TRUE(fs::is_empty(dir.path()));

    // A rename that fails (the target is a directory) leaves no temporary file either.
    const fs::path taken = dir / "taken.exr";
    fs::create_directory(taken);
    EXPECT_THROW(write_exr(img, taken.string()), IoError);
    EXPECT_TRUE(dir.files().empty());
    EXPECT_TRUE(fs::is_empty(taken));

    expect_error_naming<IoError>(
        [&] { write_png_preview(img, "radiance", (missing / "p.png").string()); },
        (missing / "p.png").string());
    EXPECT_FALSE(fs::exists(missing));
}

// --- PNG preview -------------------------------------------------------------------------------

// The sRGB transfer curve (IEC 61966-2-1), written out here independently of the library.
int expected_byte(double linear, double exposure) {
    double v = linear * std::pow(2.0, exposure);
    if (std::isnan(v) || v < 0) v = 0;
    if (v > 1) v = 1;
    const double s = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
    return static_cast<int>(std::floor(s * 255.0 + 0.5));
}

TEST(PngPreview, MapsLinearValuesToSrgbBytes) {
    const float inf = std::numeric_limits<float>::infinity();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const std::vector<float> values = {0.18f, 0.5f, 0.002f, 1.0f,       0.0f,  -0.3f,
                                       7.0f,  inf,  nan,    0.0031308f, 0.04f, 0.75f};
    // 2 x 2 pixels, values in row-major order so that a flipped image is noticed.
    LayeredImage img(2, 2);
    ImageLayer& rad = img.add_layer("radiance", std::vector<std::string>{"R", "G", "B", "A"});
    for (size_t i = 0; i < values.size(); ++i) {
        const int px = static_cast<int>(i / 3), c = static_cast<int>(i % 3);
        rad.at(px % 2, px / 2, c) = values[i];
        rad.at(px % 2, px / 2, 3) = 0.25f;  // alpha is ignored
    }
    ImageLayer& depth = img.add_layer("depth", 1);
    for (int i = 0; i < 4; ++i) depth.at(i % 2, i / 2) = values[static_cast<size_t>(i)];
    TempDir dir;
    for (double exposure : {0.0, 1.0, -2.5}) {
        const std::string path = (dir / "preview.png").string();
        write_png_preview(img, "radiance", path, exposure);
        const testing::RgbImage png = testing::read_png(path);
        ASSERT_EQ(png.width, 2);
        ASSERT_EQ(png.height, 2);
        ASSERT_EQ(png.rgb.size(), values.size());
        for (size_t i = 0; i < values.size(); ++i)
            EXPECT_EQ(png.rgb[i], expected_byte(values[i], exposure))
                << "value " << values[i] << " exposure " << exposure;

        write_png_preview(img, "depth", path, exposure);
        const testing::RgbImage grey = testing::read_png(path);
        for (size_t i = 0; i < 12; ++i)
            EXPECT_EQ(grey.rgb[i], expected_byte(values[i / 3], exposure));
    }
    // Spot checks of the formula itself: mid-grey 0.18 is sRGB 118, 0.5 is 188.
    EXPECT_EQ(expected_byte(0.18, 0), 118);
    EXPECT_EQ(expected_byte(0.5, 0), 188);
    EXPECT_EQ(dir.files(), (std::vector<std::string>{"preview.png"}));
}

TEST(PngPreview, RejectsUnsuitableLayers) {
    LayeredImage img(2, 2);
    img.add_layer("normal", std::vector<std::string>{"X", "Y", "Z"});
    img.add_layer("radiance", 3);
    TempDir dir;
    const std::string path = (dir / "p.png").string();
    EXPECT_THROW(write_png_preview(img, "normal", path), std::invalid_argument);
    EXPECT_THROW(write_png_preview(img, "nope", path), std::invalid_argument);
    EXPECT_THROW(write_png_preview(img, "radiance", path, std::nan("")), std::invalid_argument);
    EXPECT_TRUE(dir.files().empty());
}

}  // namespace
}  // namespace ssslab
