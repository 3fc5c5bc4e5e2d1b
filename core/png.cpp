#include "core/png.h"

#include <zlib.h>

#include <stdexcept>

namespace ssslab {

namespace {

void put_u32(std::string& s, unsigned long v) {
    s += static_cast<char>((v >> 24) & 0xff);
    s += static_cast<char>((v >> 16) & 0xff);
    s += static_cast<char>((v >> 8) & 0xff);
    s += static_cast<char>(v & 0xff);
}

void chunk(std::string& png, const char* type, const std::string& data) {
    put_u32(png, data.size());
    std::string body(type, 4);
    body += data;
    png += body;
    put_u32(png,
            crc32(0L, reinterpret_cast<const Bytef*>(body.data()), static_cast<uInt>(body.size())));
}

}  // namespace

std::string encode_png_rgb8(int width, int height, const std::vector<unsigned char>& rgb) {
    if (width <= 0 || height <= 0 ||
        rgb.size() != static_cast<size_t>(width) * static_cast<size_t>(height) * 3)
        throw std::invalid_argument("encode_png_rgb8: size mismatch");
    // Each row starts with filter type 0 (none).
    std::string raw;
    raw.reserve(static_cast<size_t>(height) * (static_cast<size_t>(width) * 3 + 1));
    for (int y = 0; y < height; ++y) {
        raw += '\0';
        raw.append(reinterpret_cast<const char*>(rgb.data()) + static_cast<size_t>(y) * width * 3,
                   static_cast<size_t>(width) * 3);
    }
    uLongf bound = compressBound(static_cast<uLong>(raw.size()));
    std::string z(bound, '\0');
    if (compress2(reinterpret_cast<Bytef*>(z.data()), &bound,
                  reinterpret_cast<const Bytef*>(raw.data()), static_cast<uLong>(raw.size()),
                  6) != Z_OK)
        throw std::runtime_error("encode_png_rgb8: zlib failed");
    z.resize(bound);
    std::string png("\x89PNG\r\n\x1a\n", 8);
    std::string ihdr;
    put_u32(ihdr, static_cast<unsigned long>(width));
    put_u32(ihdr, static_cast<unsigned long>(height));
    ihdr += '\x08';  // bit depth
    ihdr += '\x02';  // colour type: RGB
    ihdr += '\0';    // compression
    ihdr += '\0';    // filter
    ihdr += '\0';    // interlace
    chunk(png, "IHDR", ihdr);
    chunk(png, "IDAT", z);
    chunk(png, "IEND", "");
    return png;
}

}  // namespace ssslab
