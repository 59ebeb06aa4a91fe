// Image files: PNG read/write through libpng, JPEG read through libjpeg (Debian: libjpeg-turbo). This is
// rsvio's only image I/O; OpenCV's imgcodecs is left to the tests, because on Debian it loads GDAL and
// about 140 other libraries (42 MB of RSS before the first frame, docs/performance.md).
//
// readImage() returns what cv::imread(path, cv::IMREAD_UNCHANGED) returns for the same file, pixel for
// pixel (tests/framework/io/image_file_test.cpp checks it against OpenCV):
// - The format is chosen by the file's first bytes, never by its name: the PNG signature
//   89 50 4E 47 0D 0A 1A 0A, or the JPEG start FF D8 FF. Anything else is an ImageError.
// - PNG grey: CV_8UC1, or CV_16UC1 for 16-bit files. Bit depths 1, 2 and 4 are expanded to 0..255 as
//   OpenCV does (value * 255 / (2^depth - 1)). A tRNS chunk of a grey image is ignored.
// - PNG colour (RGB): CV_8UC3 / CV_16UC3 in OpenCV's BGR order; with a tRNS chunk, BGRA (CV_8UC4 /
//   CV_16UC4, the key colour with alpha 0, every other pixel opaque).
// - PNG with alpha (RGBA): BGRA, CV_8UC4 / CV_16UC4.
// - PNG grey + alpha: BGRA as well (B = G = R = the grey value), as OpenCV; not a 2-channel image.
// - PNG palette: expanded to BGR (CV_8UC3), or to BGRA when the palette has a tRNS chunk.
// - 16-bit samples are stored big-endian in the file and returned in the host's byte order.
// - Interlaced (Adam7) PNGs are de-interlaced. Gamma, colour-profile and other ancillary chunks are not
//   applied (as OpenCV): the samples are returned as stored.
// - JPEG grey: CV_8UC1; JPEG colour (YCbCr or RGB): CV_8UC3, BGR. Decoded with libjpeg's defaults (the
//   accurate integer IDCT, fancy upsampling), which are OpenCV's too; the EXIF orientation is not
//   applied (neither does IMREAD_UNCHANGED). CMYK/YCCK JPEGs are refused (OpenCV converts them to BGR).
// - Stricter than OpenCV: a JPEG whose compressed data ends early or is damaged is an error (OpenCV
//   returns it with the missing part grey and prints a warning); libjpeg warnings that leave the pixels
//   intact (e.g. extra bytes between markers) are ignored. libpng's warnings (a bad ancillary chunk) are
//   ignored too; nothing is printed to stderr.
// - At most 2^20 pixels per side and 2^30 pixels in all (OpenCV's limits).
//
// Errors are one line naming the file: "<path>: <reason>", e.g. "x.png: cannot decode PNG: the file is
// truncated (it ends at byte 1024)". Truncated, corrupt, empty or unknown files throw ImageError, never
// crash; libpng's errors return through setjmp/longjmp inside functions that own no C++ object, and
// libjpeg's through its error_exit hook the same way.
#pragma once
#include <opencv2/core.hpp>
#include <string>

#include "rsvio/core/error.h"

namespace rsvio::io {

// A file that cannot be read or decoded as an image. what() is "<path>: <reason>"; reason() is the part
// after the path, for callers that name the file their own way (a frame and its timestamp).
class ImageError : public DataError {
 public:
  ImageError(const std::string& path, const std::string& reason) : DataError(path + ": " + reason), reason_(reason) {}
  const std::string& reason() const { return reason_; }

 private:
  std::string reason_;
};

// True when the file starts with the 8-byte PNG signature: a cheap check of a file named .png before
// decoding, so that another format renamed, an empty or a truncated file gets a message that says so.
bool hasPngSignature(const std::string& path);

// Reads a PNG or JPEG file with cv::imread(IMREAD_UNCHANGED)'s result (see above). Throws ImageError.
cv::Mat readImage(const std::string& path);

// Writes `img` (CV_8UC1, CV_16UC1, CV_8UC3 in BGR order, or CV_8UC4 BGRA) as a PNG: grey, 16-bit grey,
// RGB or RGBA, not interlaced, no ancillary chunks. compression is zlib's level, 0 (none, fastest) to 9
// (smallest); the filters and strategy are OpenCV's for IMWRITE_PNG_COMPRESSION, so the file has the
// bytes cv::imwrite(path, img, {IMWRITE_PNG_COMPRESSION, compression}) writes. The file appears whole
// or not at all (writeFileAtomic). Throws rsvio::Error naming the file on another type, an empty image,
// a compression level outside 0..9, or a failed write.
void writePng(const std::string& path, const cv::Mat& img, int compression);

}  // namespace rsvio::io
