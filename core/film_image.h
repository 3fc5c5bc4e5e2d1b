// A multi-layer float image (the ground-truth renders: radiance, subsurface, specular, stderr,
// depth, normal, ...) with OpenEXR I/O and an 8-bit sRGB PNG preview (docs/architecture.md,
// "Formats").
//
// In an EXR file a layer is a group of channels named "<layer>.<channel>", OpenEXR's convention
// for layered files (the layer name is everything before the last dot), so that exrheader,
// OpenImageIO, Nuke and Blender show the layers: an RGB layer "radiance" is stored as the
// channels "radiance.R", "radiance.G", "radiance.B", a one-channel layer "depth" as "depth.Y" by
// default (or "depth.Z" when its channel is named "Z"). The layer with the empty name "" is the
// default layer: its channels are stored without a prefix ("R", "G", "B"), which is what viewers
// show as the main image, and channels without a dot in a file are read into it.
#pragma once

#include <deque>
#include <map>
#include <span>
#include <string>
#include <vector>

namespace ssslab {

/// One named layer of a LayeredImage: channels().size() 32-bit floats per pixel, interleaved
/// (x, y, c) -> pixels()[(y * width + x) * channels + c], row-major, pixel (0, 0) top-left.
/// Its size is fixed when the layer is added; only the values can change.
class ImageLayer {
  public:
    /// Layer name ("" is the default layer).
    const std::string& name() const { return name_; }
    int width() const { return width_; }
    int height() const { return height_; }
    /// Number of channels per pixel.
    int channels() const { return static_cast<int>(channel_names_.size()); }
    /// Channel names without the layer prefix, e.g. {"R", "G", "B"} or {"Y"}.
    const std::vector<std::string>& channel_names() const { return channel_names_; }
    /// The full EXR channel name of channel `c`: "<layer>.<channel>", or "<channel>" for "".
    std::string exr_channel_name(int c) const;

    /// Value of channel `c` at pixel (x, y); not bounds-checked.
    float& at(int x, int y, int c = 0) { return pixels_[index(x, y, c)]; }
    float at(int x, int y, int c = 0) const { return pixels_[index(x, y, c)]; }
    /// All values, interleaved as described above.
    std::span<float> pixels() { return pixels_; }
    std::span<const float> pixels() const { return pixels_; }

  private:
    friend class LayeredImage;
    ImageLayer(std::string name, int width, int height, std::vector<std::string> channel_names,
               std::vector<float> pixels);
    size_t index(int x, int y, int c) const {
        return (static_cast<size_t>(y) * static_cast<size_t>(width_) + static_cast<size_t>(x)) *
                   channel_names_.size() +
               static_cast<size_t>(c);
    }

    std::string name_;
    int width_ = 0;
    int height_ = 0;
    std::vector<std::string> channel_names_;
    std::vector<float> pixels_;
};

/// A width x height image made of an ordered list of uniquely named float layers, plus string
/// metadata (stored as EXR header string attributes, e.g. "ssslab.spp", "ssslab.seed").
/// Misuse (unknown or duplicate layer names, wrong sizes, invalid names) throws
/// std::invalid_argument with a message that names the layer.
class LayeredImage {
  public:
    /// An image without layers. Throws std::invalid_argument unless width, height >= 1.
    LayeredImage(int width, int height);

    int width() const { return width_; }
    int height() const { return height_; }

    /// Add a zero-filled layer with `channels` channels named by default: 1 -> {"Y"},
    /// 3 -> {"R", "G", "B"}; other counts need explicit names. References to layers stay valid
    /// when more layers are added.
    ImageLayer& add_layer(const std::string& name, int channels);
    /// Add a layer with default channel names (as above) and the given interleaved values
    /// (width * height * channels of them).
    ImageLayer& add_layer(const std::string& name, int channels, std::vector<float> pixels);
    /// Add a layer with explicit channel names (non-empty, without '.', unique) and either no
    /// values (zero-filled) or width * height * channel_names.size() interleaved values.
    ImageLayer& add_layer(const std::string& name, std::vector<std::string> channel_names,
                          std::vector<float> pixels = {});

    /// Whether a layer of that name exists.
    bool has_layer(const std::string& name) const;
    /// The layer of that name; throws std::invalid_argument listing the layers if there is none.
    ImageLayer& layer(const std::string& name);
    const ImageLayer& layer(const std::string& name) const;
    /// All layers, in the order they were added (read_exr: sorted by name, see there).
    const std::deque<ImageLayer>& layers() const { return layers_; }

    /// String metadata, written as EXR string attributes. Keys should be namespaced
    /// ("ssslab.spp"); write_exr rejects keys that are standard EXR attributes.
    std::map<std::string, std::string>& metadata() { return metadata_; }
    const std::map<std::string, std::string>& metadata() const { return metadata_; }

  private:
    int width_ = 0;
    int height_ = 0;
    std::deque<ImageLayer> layers_;  // deque: add_layer keeps references to earlier layers valid
    std::map<std::string, std::string> metadata_;
};

/// Write `image` as a single-part scanline OpenEXR file: every channel as 32-bit FLOAT, ZIP
/// compression, data window = display window = [0, width) x [0, height), each layer's channels
/// named "<layer>.<channel>", metadata as string attributes. The file is encoded in memory and
/// written atomically (temporary name in the same directory, then rename). The parent directory
/// must exist. Throws std::invalid_argument for an image without layers or a metadata key that
/// is empty or a standard EXR attribute, IoError if the file cannot be written (no partial or
/// temporary file is left behind).
void write_exr(const LayeredImage& image, const std::string& path);
/// The bytes write_exr writes (for an OutputTransaction); `path` only names the file in errors.
std::string encode_exr(const LayeredImage& image, const std::string& path);

/// Read an OpenEXR file: scanline or tiled (level 0 of a mip/rip-mapped file), HALF, FLOAT or
/// UINT channels (converted to float), single- or multi-part (the channels of all parts are
/// merged; their display windows must agree).
/// - The image covers the display window, whose top-left corner becomes pixel (0, 0); pixels
///   outside the data window read as 0, data outside the display window is dropped.
/// - Channels are grouped into layers by the name before their last dot ("diffuse.direct.R" ->
///   layer "diffuse.direct", channel "R"); channels without a dot form the default layer "".
///   Layers come sorted by name (EXR stores channels sorted, so the written order is not kept);
///   within a layer, channels are ordered R, G, B, X, Y, Z, A, then any others by name.
/// - metadata() holds every string attribute of the header(s) except OpenEXR's own "name" and
///   "type" (the first part wins where parts disagree); attributes of other types are not read.
/// Throws InputError naming the file and the problem for a missing or unreadable file, a file
/// that is not an EXR, a truncated or corrupt EXR (headers and chunk table are checked against
/// the file through OpenEXRCore before anything is decoded), and for what is not supported
/// (deep data, subsampled channels, a channel name in two parts, more than 2^31 samples).
LayeredImage read_exr(const std::string& path);

/// A linear value as an 8-bit sRGB code, the encoding of write_png_preview below (clamped to
/// [0, 1], NaN and negatives 0).
unsigned char srgb8(double linear);

/// Write an 8-bit sRGB PNG preview of one layer: each value is scaled by 2^exposure, clamped to
/// [0, 1] (NaN -> 0), encoded with the sRGB transfer curve (IEC 61966-2-1: 12.92 v for
/// v <= 0.0031308, else 1.055 v^(1/2.4) - 0.055) and rounded to the nearest of 0..255. The
/// layer must have channels R, G, B (others, e.g. A, are ignored) or exactly one channel (shown
/// as grey). Written atomically; the parent directory must exist. Throws std::invalid_argument
/// for an unknown or unsuitable layer or a non-finite exposure, IoError if the file cannot be
/// written.
void write_png_preview(const LayeredImage& image, const std::string& layer, const std::string& path,
                       double exposure = 0);
/// The bytes write_png_preview writes (for an OutputTransaction).
std::string encode_png_preview(const LayeredImage& image, const std::string& layer,
                               double exposure = 0);

}  // namespace ssslab
