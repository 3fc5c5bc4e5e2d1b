// Images in the formats other programs read and write, through OpenImageIO: PNG previews of
// reports and renders, and any image another renderer wrote (EXR, HDR, PNG, TIFF, ...) as a
// LayeredImage for `ssslab compare`. ssslab's own EXR files go through core/film_image.h
// (OpenEXR directly: layers, standard-error layers and metadata, checked before decoding).
#pragma once

#include "core/film_image.h"

#include <string>
#include <vector>

namespace ssslab {

/// The bytes of a PNG file of `width` x `height` 8-bit RGB pixels (row-major, 3 bytes each,
/// sRGB-encoded: the file says so). Deterministic: the same pixels give the same bytes. Throws
/// std::invalid_argument for a size mismatch.
std::string encode_png_rgb8(int width, int height, const std::vector<unsigned char>& rgb);

/// Read an image of any format OpenImageIO reads. EXR files go through read_exr (every layer
/// and its metadata); any other format becomes the default layer "" with the file's channel
/// names (R, G, B, ...; an alpha channel beside three colours goes to a layer "alpha"), as
/// float, linear: integer pixels are decoded by the transfer function the file declares (sRGB:
/// PNG, JPEG and files that declare none; Rec. 709: PNM; alpha as stored); float formats (HDR,
/// float TIFF) are taken as linear. Level 0 of a file of one image: a file of several (subimages:
/// a multi-page TIFF, an animated GIF) is refused. Metadata "ssslab.format" (the
/// reader's name) and "ssslab.decoding" (how the values became linear). Throws InputError naming
/// the file for a missing or unreadable file, one OpenImageIO cannot read or one of several
/// images.
LayeredImage read_image(const std::string& path);

}  // namespace ssslab
