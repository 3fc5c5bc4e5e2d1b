#include "core/image_io.h"

#include "core/error.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>

#include <cmath>
#include <filesystem>
#include <stdexcept>

namespace ssslab {

namespace {

// The sRGB EOTF (IEC 61966-2-1): an encoded value in [0, 1] to linear.
float srgb_to_linear(float v) {
    return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

// The inverse of the Rec. 709 OETF (ITU-R BT.709), what OpenImageIO calls "Rec709" (e.g. PNM).
float rec709_to_linear(float v) {
    return v < 0.081f ? v / 4.5f : std::pow((v + 0.099f) / 1.099f, 1.0f / 0.45f);
}

}  // namespace

std::string encode_png_rgb8(int width, int height, const std::vector<unsigned char>& rgb) {
    if (width <= 0 || height <= 0 ||
        rgb.size() != static_cast<size_t>(width) * static_cast<size_t>(height) * 3)
        throw std::invalid_argument("encode_png_rgb8: size mismatch");
    std::vector<unsigned char> bytes;
    OIIO::Filesystem::IOVecOutput out_proxy(bytes);
    auto out = OIIO::ImageOutput::create("png");
    if (!out) throw std::runtime_error("encode_png_rgb8: OpenImageIO has no PNG writer");
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:ColorSpace", "sRGB");
    spec.attribute("png:compressionLevel", 6);
    if (!out->set_ioproxy(&out_proxy) || !out->open("memory.png", spec) ||
        !out->write_image(OIIO::TypeDesc::UINT8, rgb.data()) || !out->close())
        throw std::runtime_error("encode_png_rgb8: " + out->geterror());
    return std::string(bytes.begin(), bytes.end());
}

LayeredImage read_image(const std::string& path) {
    const auto fail = [&](const std::string& what) -> LayeredImage {
        throw InputError({path, 0, 0}, "", what);
    };
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) return fail("no such file");
    auto in = OIIO::ImageInput::open(path);
    if (!in) return fail("not an image OpenImageIO can read: " + OIIO::geterror());
    const std::string format = in->format_name();
    if (format == "openexr") {
        in->close();
        return read_exr(path);  // every layer, the standard errors and the metadata
    }
    // A file of several images (a multi-page TIFF, an animated GIF) is
    // refused: which of them a comparison should read is not ours to guess.
    if (in->seek_subimage(1, 0)) {
        int n = 2;
        while (n < 1000 && in->seek_subimage(n, 0)) ++n;
        return fail("a " + format + " file of " + (n < 1000 ? std::to_string(n) : "1000 or more") +
                    " images (subimages); ssslab reads a file of one image: save the one to use "
                    "as a file of its own");
    }
    if (!in->seek_subimage(0, 0)) return fail("cannot read its first image: " + in->geterror());
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 || spec.depth > 1)
        return fail("a " + format + " image of " + std::to_string(spec.width) + " x " +
                    std::to_string(spec.height) + " pixels and " + std::to_string(spec.nchannels) +
                    " channels is not a 2D image");
    if (static_cast<double>(spec.width) * spec.height * spec.nchannels > 2147483647.0)
        return fail("too large (more than 2^31 samples)");
    std::vector<float> px(static_cast<size_t>(spec.width) * static_cast<size_t>(spec.height) *
                          static_cast<size_t>(spec.nchannels));
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, px.data()))
        return fail("cannot decode the " + format + " image: " + in->geterror());
    // Integer pixels are encoded values: decode them to linear by the transfer function the file
    // declares (sRGB when it declares none).
    const std::string cs = OIIO::Strutil::lower(spec.get_string_attribute("oiio:ColorSpace"));
    const bool integer = !spec.format.is_floating_point();
    float (*decode)(float) = nullptr;
    std::string decoding = "linear";
    if (integer && (cs == "srgb" || cs.empty())) {
        decode = srgb_to_linear;
        decoding = "sRGB to linear";
    } else if (integer && cs == "rec709") {
        decode = rec709_to_linear;
        decoding = "Rec. 709 to linear";
    } else if (integer && cs != "linear") {
        decoding = "as stored (colour space " + cs + ")";
    }
    std::vector<std::string> names;
    const int alpha = spec.alpha_channel;
    for (int c = 0; c < spec.nchannels; ++c) {
        std::string n = c < static_cast<int>(spec.channelnames.size()) ? spec.channelnames[c] : "";
        if (n.empty() || n.find('.') != std::string::npos) n = "C" + std::to_string(c);
        names.push_back(n);
    }
    if (decode)
        for (size_t i = 0; i < px.size(); ++i)
            if (static_cast<int>(i % static_cast<size_t>(spec.nchannels)) != alpha)
                px[i] = decode(px[i]);
    LayeredImage img(spec.width, spec.height);
    try {
        if (alpha >= 0 && spec.nchannels == 4) {
            // Colour in the default layer, alpha in a layer of its own ("alpha.A").
            std::vector<float> colour, a;
            std::vector<std::string> colour_names;
            for (int c = 0; c < 4; ++c)
                if (c != alpha) colour_names.push_back(names[static_cast<size_t>(c)]);
            for (size_t i = 0; i < px.size(); ++i)
                (static_cast<int>(i % 4) == alpha ? a : colour).push_back(px[i]);
            img.add_layer("", colour_names, std::move(colour));
            img.add_layer("alpha", std::vector<std::string>{"A"}, std::move(a));
        } else {
            img.add_layer("", names, std::move(px));
        }
    } catch (const std::invalid_argument& e) {
        return fail(std::string("channels: ") + e.what());
    }
    img.metadata()["ssslab.format"] = format;
    img.metadata()["ssslab.decoding"] = decoding;
    return img;
}

}  // namespace ssslab
