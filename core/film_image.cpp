#include "core/film_image.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_io.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputPart.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfPartType.h>
#include <OpenEXR/ImfStdIO.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/openexr.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <set>
#include <stdexcept>
#include <string_view>
#include <utility>

namespace ssslab {

namespace fs = std::filesystem;

namespace {

// EXR channel names are at most 255 bytes (OpenEXR's long-name limit).
constexpr size_t kMaxExrNameLength = 255;
// Refuse images of more than 2^31 float samples (8 GiB) before allocating: a corrupt header
// must give an InputError, not an out-of-memory kill.
constexpr int64_t kMaxSamples = int64_t{1} << 31;

std::vector<std::string> default_channel_names(const std::string& layer, int channels) {
    if (channels == 1) return {"Y"};
    if (channels == 3) return {"R", "G", "B"};
    throw std::invalid_argument("layer '" + layer + "': " + std::to_string(channels) +
                                " channels need explicit channel names (defaults exist for 1 "
                                "and 3)");
}

void check_layer_name(const std::string& name) {
    // "" is the default layer. Dots separate nested layers ("diffuse.direct"), so a name must not
    // start or end with one, nor have an empty part.
    if (name.empty()) return;
    if (name.front() == '.' || name.back() == '.' || name.find("..") != std::string::npos)
        throw std::invalid_argument("layer name '" + name +
                                    "': must not start or end with '.' or contain '..'");
}

void check_channel_names(const std::string& layer, const std::vector<std::string>& names) {
    if (names.empty())
        throw std::invalid_argument("layer '" + layer + "': needs at least one channel");
    std::set<std::string> seen;
    for (const auto& n : names) {
        if (n.empty() || n.find('.') != std::string::npos)
            throw std::invalid_argument("layer '" + layer + "': channel name '" + n +
                                        "' must be non-empty and contain no '.'");
        if (!seen.insert(n).second)
            throw std::invalid_argument("layer '" + layer + "': duplicate channel name '" + n +
                                        "'");
        const size_t full = (layer.empty() ? 0 : layer.size() + 1) + n.size();
        if (full > kMaxExrNameLength)
            throw std::invalid_argument("layer '" + layer + "': EXR channel name longer than " +
                                        std::to_string(kMaxExrNameLength) + " bytes");
    }
}

std::string layer_list(const std::deque<ImageLayer>& layers) {
    if (layers.empty()) return "(none)";
    std::string s;
    for (const auto& l : layers) {
        if (!s.empty()) s += ", ";
        s += "'" + l.name() + "'";
    }
    return s;
}

// Output files are not created in directories that do not exist (see write_exr).
void check_parent_directory(const std::string& path, const char* what) {
    const fs::path parent = fs::path(path).parent_path();
    if (parent.empty()) return;
    std::error_code ec;
    if (!fs::is_directory(parent, ec))
        throw IoError(std::string(what) + ": cannot write '" + path + "': directory '" +
                      parent.string() + "' does not exist");
}

// Order of channels within a layer on reading: colour, then vector, then alpha, then the rest.
int channel_rank(const std::string& c) {
    static constexpr std::array<const char*, 7> kOrder = {"R", "G", "B", "X", "Y", "Z", "A"};
    for (size_t i = 0; i < kOrder.size(); ++i)
        if (c == kOrder[i]) return static_cast<int>(i);
    return static_cast<int>(kOrder.size());
}

// Metadata keys that OpenEXR itself writes or reserves, besides those already in a Header.
bool reserved_attribute(const std::string& key) {
    static constexpr std::array<std::string_view, 8> kReserved = {
        "tiles", "type",     "name", "version", "chunkCount", "maxSamplesPerPixel",
        "view",  "multiView"};
    return std::find(kReserved.begin(), kReserved.end(), key) != kReserved.end();
}

double srgb_encode(double v) {
    if (!(v > 0)) return 0;  // negative and NaN
    if (v >= 1) return 1;
    return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
}

// A structural check through OpenEXRCore, before the C++ reader: the headers, and the leader
// (position and declared size) of every chunk of every level, are validated against the file
// without decoding anything. OpenEXR 3.1's C++ reader trusts declared sizes and allocates them
// first (a corrupt string attribute size costs 1.5 GB before the read fails); the Core library
// checks them against the file size. Returns an empty string if the file looks sound.
std::string exr_structure_problem(const std::string& path) {
    std::string message;  // the latest message of the Core library
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.user_data = &message;
    init.error_handler_fn = [](exr_const_context_t ctxt, exr_result_t code, const char* msg) {
        void* user = nullptr;
        if (exr_get_user_data(ctxt, &user) == EXR_ERR_SUCCESS && user)
            *static_cast<std::string*>(user) = msg ? msg : exr_get_default_error_message(code);
    };
    const auto describe = [&](exr_result_t rv, const std::string& where = {}) {
        return where + (message.empty() ? std::string(exr_get_default_error_message(rv)) : message);
    };
    exr_context_t ctxt = nullptr;
    const exr_result_t started = exr_start_read(&ctxt, path.c_str(), &init);
    struct Finish {
        exr_context_t* ctxt;
        ~Finish() {
            if (*ctxt) exr_finish(ctxt);
        }
    } finish{&ctxt};
    if (started != EXR_ERR_SUCCESS) return describe(started);
    int parts = 0;
    exr_result_t rv = exr_get_count(ctxt, &parts);
    if (rv != EXR_ERR_SUCCESS) return describe(rv);
    for (int p = 0; p < parts; ++p) {
        const std::string part = "part " + std::to_string(p) + ", ";
        exr_storage_t storage{};
        exr_attr_box2i_t dw{};
        if ((rv = exr_get_storage(ctxt, p, &storage)) != EXR_ERR_SUCCESS ||
            (rv = exr_get_data_window(ctxt, p, &dw)) != EXR_ERR_SUCCESS)
            return describe(rv, part);
        exr_chunk_info_t info{};
        if (storage == EXR_STORAGE_SCANLINE) {
            int32_t lines = 0;
            if ((rv = exr_get_scanlines_per_chunk(ctxt, p, &lines)) != EXR_ERR_SUCCESS)
                return describe(rv, part);
            for (int64_t y = dw.min.y; y <= dw.max.y; y += std::max(lines, 1))
                if ((rv = exr_read_scanline_chunk_info(ctxt, p, static_cast<int>(y), &info)) !=
                    EXR_ERR_SUCCESS)
                    return describe(rv, part + "scanline " + std::to_string(y) + ": ");
        } else if (storage == EXR_STORAGE_TILED) {
            // All levels, although only level 0 is read: a file cut short in its mip levels is
            // still a truncated file.
            uint32_t txs = 0, tys = 0;
            exr_tile_level_mode_t mode{};
            exr_tile_round_mode_t round{};
            int32_t nlx = 0, nly = 0;
            if ((rv = exr_get_tile_descriptor(ctxt, p, &txs, &tys, &mode, &round)) !=
                    EXR_ERR_SUCCESS ||
                (rv = exr_get_tile_levels(ctxt, p, &nlx, &nly)) != EXR_ERR_SUCCESS)
                return describe(rv, part);
            for (int ly = 0; ly < nly; ++ly)
                for (int lx = 0; lx < nlx; ++lx) {
                    if (mode != EXR_TILE_RIPMAP_LEVELS && lx != ly) continue;
                    int32_t tw = 0, th = 0, lw = 0, lh = 0;
                    if ((rv = exr_get_tile_sizes(ctxt, p, lx, ly, &tw, &th)) != EXR_ERR_SUCCESS ||
                        (rv = exr_get_level_sizes(ctxt, p, lx, ly, &lw, &lh)) != EXR_ERR_SUCCESS)
                        return describe(rv, part);
                    if (tw < 1 || th < 1) return part + "invalid tile size";
                    for (int ty = 0; ty < (lh + th - 1) / th; ++ty)
                        for (int tx = 0; tx < (lw + tw - 1) / tw; ++tx)
                            if ((rv = exr_read_tile_chunk_info(ctxt, p, tx, ty, lx, ly, &info)) !=
                                EXR_ERR_SUCCESS)
                                return describe(rv, part + "level (" + std::to_string(lx) + ", " +
                                                        std::to_string(ly) + ") tile (" +
                                                        std::to_string(tx) + ", " +
                                                        std::to_string(ty) + "): ");
                }
        }
        // Deep parts are refused by read_exr with its own message.
    }
    return {};
}

// A channel of a file to be read: which part it is in, its full name, layer and channel name.
struct FileChannel {
    int part = 0;
    std::string full;
    std::string layer;
    std::string channel;
};

}  // namespace

unsigned char srgb8(double linear) {
    return static_cast<unsigned char>(std::lround(srgb_encode(linear) * 255.0));
}

// --- ImageLayer, LayeredImage ---------------------------------------------------------------

ImageLayer::ImageLayer(std::string name, int width, int height,
                       std::vector<std::string> channel_names, std::vector<float> pixels)
    : name_(std::move(name)),
      width_(width),
      height_(height),
      channel_names_(std::move(channel_names)),
      pixels_(std::move(pixels)) {}

std::string ImageLayer::exr_channel_name(int c) const {
    const std::string& ch = channel_names_.at(static_cast<size_t>(c));
    return name_.empty() ? ch : name_ + "." + ch;
}

LayeredImage::LayeredImage(int width, int height) : width_(width), height_(height) {
    if (width < 1 || height < 1)
        throw std::invalid_argument("LayeredImage: size " + std::to_string(width) + " x " +
                                    std::to_string(height) + " must be at least 1 x 1");
    if (static_cast<int64_t>(width) * height > kMaxSamples)
        throw std::invalid_argument("LayeredImage: size " + std::to_string(width) + " x " +
                                    std::to_string(height) + " is too large");
}

ImageLayer& LayeredImage::add_layer(const std::string& name, int channels) {
    return add_layer(name, default_channel_names(name, channels), {});
}

ImageLayer& LayeredImage::add_layer(const std::string& name, int channels,
                                    std::vector<float> pixels) {
    return add_layer(name, default_channel_names(name, channels), std::move(pixels));
}

ImageLayer& LayeredImage::add_layer(const std::string& name, std::vector<std::string> channel_names,
                                    std::vector<float> pixels) {
    check_layer_name(name);
    check_channel_names(name, channel_names);
    if (has_layer(name))
        throw std::invalid_argument("layer '" + name +
                                    "' already exists (layers: " + layer_list(layers_) + ")");
    const size_t n =
        static_cast<size_t>(width_) * static_cast<size_t>(height_) * channel_names.size();
    if (pixels.empty()) {
        pixels.assign(n, 0.0f);
    } else if (pixels.size() != n) {
        throw std::invalid_argument("layer '" + name + "': " + std::to_string(pixels.size()) +
                                    " values given, " + std::to_string(n) + " expected (" +
                                    std::to_string(width_) + " x " + std::to_string(height_) +
                                    " x " + std::to_string(channel_names.size()) + " channels)");
    }
    layers_.push_back(
        ImageLayer(name, width_, height_, std::move(channel_names), std::move(pixels)));
    return layers_.back();
}

bool LayeredImage::has_layer(const std::string& name) const {
    return std::any_of(layers_.begin(), layers_.end(),
                       [&](const ImageLayer& l) { return l.name() == name; });
}

ImageLayer& LayeredImage::layer(const std::string& name) {
    for (auto& l : layers_)
        if (l.name() == name) return l;
    throw std::invalid_argument("no layer '" + name + "' (layers: " + layer_list(layers_) + ")");
}

const ImageLayer& LayeredImage::layer(const std::string& name) const {
    return const_cast<LayeredImage*>(this)->layer(name);
}

// --- OpenEXR ---------------------------------------------------------------------------------

std::string encode_exr(const LayeredImage& image, const std::string& path) {
    if (image.layers().empty())
        throw std::invalid_argument("write_exr: '" + path + "': the image has no layers");
    Imf::Header header(image.width(), image.height());
    header.compression() = Imf::ZIP_COMPRESSION;
    header.lineOrder() = Imf::INCREASING_Y;
    for (const auto& [key, value] : image.metadata()) {
        if (key.empty() || key.size() > kMaxExrNameLength || reserved_attribute(key) ||
            header.find(key) != header.end())
            throw std::invalid_argument("write_exr: '" + path + "': metadata key '" + key +
                                        "' is empty, too long or a standard EXR attribute");
        header.insert(key, Imf::StringAttribute(value));
    }

    Imf::FrameBuffer fb;
    for (const auto& l : image.layers()) {
        const size_t xstride = sizeof(float) * static_cast<size_t>(l.channels());
        for (int c = 0; c < l.channels(); ++c) {
            const std::string name = l.exr_channel_name(c);
            header.channels().insert(name, Imf::Channel(Imf::FLOAT));
            fb.insert(name, Imf::Slice::Make(Imf::FLOAT, l.pixels().data() + c, Imath::V2i(0, 0),
                                             l.width(), l.height(), xstride,
                                             xstride * static_cast<size_t>(l.width())));
        }
    }

    std::string bytes;
    try {
        Imf::StdOSStream os;
        {
            // The offset table is written when the OutputFile is destroyed.
            Imf::OutputFile out(os, header);
            out.setFrameBuffer(fb);
            out.writePixels(image.height());
        }
        bytes = os.str();
    } catch (const std::exception& e) {
        throw IoError("write_exr: cannot encode '" + path + "': " + e.what());
    }
    return bytes;
}

void write_exr(const LayeredImage& image, const std::string& path) {
    std::string bytes = encode_exr(image, path);  // checks the image first, as before
    check_parent_directory(path, "write_exr");
    write_file_atomic(path, bytes);
}

LayeredImage read_exr(const std::string& path) {
    const auto fail = [&](const std::string& what) {
        return InputError(SourceLocation{path, 0, 0}, "", what);
    };
    std::error_code ec;
    const auto status = fs::status(path, ec);
    if (!fs::exists(status)) throw fail("cannot read OpenEXR image: no such file");
    if (fs::is_directory(status))
        throw fail("cannot read OpenEXR image: is a directory, not a file");
    {
        // Check the magic number first: a clearer message than OpenEXR's for a non-EXR file.
        std::ifstream in(path, std::ios::binary);
        if (!in) throw fail("cannot read OpenEXR image: cannot open the file");
        std::array<unsigned char, 4> magic{};
        in.read(reinterpret_cast<char*>(magic.data()), magic.size());
        if (in.gcount() != 4 || magic != std::array<unsigned char, 4>{0x76, 0x2f, 0x31, 0x01})
            throw fail("not an OpenEXR file (it does not start with the EXR magic number)");
    }

    if (const std::string problem = exr_structure_problem(path); !problem.empty())
        throw fail("corrupt or truncated OpenEXR file: " + problem);

    try {
        Imf::MultiPartInputFile file(path.c_str());
        const int parts = file.parts();
        if (parts < 1) throw fail("OpenEXR file has no parts");
        const Imath::Box2i disp = file.header(0).displayWindow();
        const int64_t w = int64_t{disp.max.x} - disp.min.x + 1;
        const int64_t h = int64_t{disp.max.y} - disp.min.y + 1;

        // Collect every channel of every part, and the string attributes.
        std::vector<FileChannel> channels;
        std::set<std::string> full_names;
        std::map<std::string, std::string> metadata;
        for (int p = 0; p < parts; ++p) {
            const Imf::Header& hd = file.header(p);
            const std::string part = "part " + std::to_string(p) + ": ";
            if (hd.hasType() && Imf::isDeepData(hd.type()))
                throw fail(part + "deep data (" + hd.type() + ") is not supported");
            if (hd.displayWindow() != disp)
                throw fail(part + "display window differs from that of part 0");
            for (auto it = hd.channels().begin(); it != hd.channels().end(); ++it) {
                const std::string full = it.name();
                if (it.channel().xSampling != 1 || it.channel().ySampling != 1)
                    throw fail(part + "channel '" + full + "' is subsampled (not supported)");
                if (!full_names.insert(full).second)
                    throw fail(part + "channel '" + full + "' also occurs in an earlier part");
                const size_t dot = full.rfind('.');
                FileChannel fc{p, full, "", full};
                if (dot != std::string::npos) {
                    fc.layer = full.substr(0, dot);
                    fc.channel = full.substr(dot + 1);
                }
                if (fc.channel.empty()) throw fail(part + "channel '" + full + "' has no name");
                channels.push_back(std::move(fc));
            }
            for (auto it = hd.begin(); it != hd.end(); ++it) {
                const std::string key = it.name();
                if (key == "name" || key == "type") continue;
                if (const auto* s = dynamic_cast<const Imf::StringAttribute*>(&it.attribute()))
                    metadata.emplace(key, s->value());
            }
        }
        if (channels.empty()) throw fail("OpenEXR file has no channels");
        if (w < 1 || h < 1 || w * h * static_cast<int64_t>(channels.size()) > kMaxSamples)
            throw fail("display window of " + std::to_string(w) + " x " + std::to_string(h) +
                       " pixels is empty or too large to read");

        // Group into layers: sorted by layer name, channels in canonical order.
        std::sort(channels.begin(), channels.end(), [](const FileChannel& a, const FileChannel& b) {
            if (a.layer != b.layer) return a.layer < b.layer;
            const int ra = channel_rank(a.channel), rb = channel_rank(b.channel);
            if (ra != rb) return ra < rb;
            return a.channel < b.channel;
        });
        LayeredImage image(static_cast<int>(w), static_cast<int>(h));
        image.metadata() = std::move(metadata);
        for (size_t i = 0; i < channels.size();) {
            size_t j = i;
            std::vector<std::string> names;
            for (; j < channels.size() && channels[j].layer == channels[i].layer; ++j)
                names.push_back(channels[j].channel);
            const std::string& layer_name = channels[i].layer;
            if (!layer_name.empty() && (layer_name.front() == '.' || layer_name.back() == '.' ||
                                        layer_name.find("..") != std::string::npos))
                throw fail("channel '" + channels[i].full + "' has an invalid layer name");
            image.add_layer(layer_name, std::move(names));
            i = j;
        }

        // Read each part into the layers.
        for (int p = 0; p < parts; ++p) {
            Imf::InputPart in(file, p);
            const Imath::Box2i dw = in.header().dataWindow();
            const Imath::Box2i isect(
                Imath::V2i(std::max(dw.min.x, disp.min.x), std::max(dw.min.y, disp.min.y)),
                Imath::V2i(std::min(dw.max.x, disp.max.x), std::min(dw.max.y, disp.max.y)));
            if (isect.isEmpty()) continue;  // nothing of this part is visible
            const bool inside = isect == dw;
            // Data inside the display window is read straight into the layers. Otherwise the rows
            // that meet the display window are read, in full data-window width, into one buffer
            // per channel, and the visible part copied.
            const Imath::Box2i rows(Imath::V2i(dw.min.x, isect.min.y),
                                    Imath::V2i(dw.max.x, isect.max.y));
            const int64_t row_w = int64_t{dw.max.x} - dw.min.x + 1;
            const int64_t row_h = int64_t{isect.max.y} - isect.min.y + 1;
            std::vector<std::vector<float>> buffers;
            std::vector<std::pair<ImageLayer*, int>> targets;
            Imf::FrameBuffer fb;
            for (const auto& fc : channels) {
                if (fc.part != p) continue;
                ImageLayer& l = image.layer(fc.layer);
                const auto& names = l.channel_names();
                const int c = static_cast<int>(std::find(names.begin(), names.end(), fc.channel) -
                                               names.begin());
                if (inside) {
                    const size_t xs = sizeof(float) * static_cast<size_t>(l.channels());
                    fb.insert(fc.full, Imf::Slice::Make(Imf::FLOAT, l.pixels().data() + c, disp.min,
                                                        w, h, xs, xs * static_cast<size_t>(w)));
                } else {
                    if (row_w * row_h * static_cast<int64_t>(buffers.size() + 1) > kMaxSamples)
                        throw fail("part " + std::to_string(p) + ": data window too large to read");
                    buffers.emplace_back(static_cast<size_t>(row_w * row_h));
                    targets.emplace_back(&l, c);
                    fb.insert(fc.full, Imf::Slice::Make(
                                           Imf::FLOAT, buffers.back().data(), rows, sizeof(float),
                                           sizeof(float) * static_cast<size_t>(row_w)));
                }
            }
            in.setFrameBuffer(fb);
            in.readPixels(rows.min.y, rows.max.y);
            for (size_t k = 0; k < buffers.size(); ++k) {
                auto [l, c] = targets[k];
                for (int y = isect.min.y; y <= isect.max.y; ++y)
                    for (int x = isect.min.x; x <= isect.max.x; ++x)
                        l->at(x - disp.min.x, y - disp.min.y, c) = buffers[k][static_cast<size_t>(
                            (y - rows.min.y) * row_w + (x - rows.min.x))];
            }
        }
        return image;
    } catch (const InputError&) {
        throw;
    } catch (const std::exception& e) {
        // Iex exceptions (truncated or corrupt data, unsupported features) and bad_alloc.
        throw fail(std::string("cannot read OpenEXR image (truncated or corrupt?): ") + e.what());
    }
}

// --- PNG preview -----------------------------------------------------------------------------

std::string encode_png_preview(const LayeredImage& image, const std::string& layer,
                               double exposure) {
    if (!std::isfinite(exposure))
        throw std::invalid_argument("write_png_preview: exposure must be finite");
    const ImageLayer& l = image.layer(layer);
    const auto& names = l.channel_names();
    std::array<int, 3> src{};
    if (l.channels() == 1) {
        src = {0, 0, 0};
    } else {
        for (int k = 0; k < 3; ++k) {
            const char* want = k == 0 ? "R" : k == 1 ? "G" : "B";
            const auto it = std::find(names.begin(), names.end(), want);
            if (it == names.end())
                throw std::invalid_argument("write_png_preview: layer '" + layer +
                                            "' has neither R, G, B channels nor a single channel");
            src[static_cast<size_t>(k)] = static_cast<int>(it - names.begin());
        }
    }
    const double scale = std::exp2(exposure);
    std::vector<unsigned char> rgb(static_cast<size_t>(l.width()) *
                                   static_cast<size_t>(l.height()) * 3);
    size_t o = 0;
    for (int y = 0; y < l.height(); ++y)
        for (int x = 0; x < l.width(); ++x)
            for (int k = 0; k < 3; ++k)
                rgb[o++] = srgb8(scale * l.at(x, y, src[static_cast<size_t>(k)]));
    return encode_png_rgb8(l.width(), l.height(), rgb);
}

void write_png_preview(const LayeredImage& image, const std::string& layer, const std::string& path,
                       double exposure) {
    std::string bytes = encode_png_preview(image, layer, exposure);
    check_parent_directory(path, "write_png_preview");
    write_file_atomic(path, bytes);
}

}  // namespace ssslab
