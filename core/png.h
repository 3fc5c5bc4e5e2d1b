// A minimal PNG writer (8-bit RGB, zlib through Debian's zlib1g), for the images of reports.
#pragma once

#include <string>
#include <vector>

namespace ssslab {

/// The bytes of a PNG file of `width` x `height` 8-bit RGB pixels (row-major, 3 bytes each).
std::string encode_png_rgb8(int width, int height, const std::vector<unsigned char>& rgb);

}  // namespace ssslab
