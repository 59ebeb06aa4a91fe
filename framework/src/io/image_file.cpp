// Image files (contract in rsvio/io/image_file.h): PNG through libpng, JPEG through libjpeg.
//
// Error handling. libpng and libjpeg report a fatal error through a callback that must not return; ours
// record the message and longjmp back to the setjmp of the calling stage. longjmp skips destructors, so
// every function that calls setjmp (pngReadHeader, pngReadPixels, pngEncode, jpegReadHeader,
// jpegReadPixels) holds only plain data and pointers, touches C++ objects only through pointers they were
// given, and returns false on an error; their C++ callers own the libraries' structs (RAII), the cv::Mat
// and the row pointers, and turn false into an ImageError / Error. No C++ exception passes through the C
// libraries' frames (the write callback catches its own and reports through png_error).
#include "rsvio/io/image_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <vector>

// jpeglib.h needs <cstdio> (FILE) before it.
#include <jpeglib.h>
#include <jerror.h>  // JWRN_* message codes
#include <png.h>
#include <zlib.h>

#include "rsvio/io/atomic_file.h"

namespace rsvio::io {
namespace {

constexpr bool kLittleEndian = __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__;
// OpenCV's limits (CV_IO_MAX_IMAGE_WIDTH/HEIGHT/PIXELS): larger headers are refused before allocating.
constexpr uint64_t kMaxSide = uint64_t{1} << 20;
constexpr uint64_t kMaxPixels = uint64_t{1} << 30;

const unsigned char kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
const unsigned char kJpegStart[3] = {0xFF, 0xD8, 0xFF};

// The whole file (images are read once, whole; the decoders then read from memory).
std::vector<unsigned char> readFileBytes(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw ImageError(path, std::string("cannot open image file (") + std::strerror(errno) + ")");
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0)
    throw ImageError(path, std::string("cannot read image file (") + std::strerror(errno) + ")");
  if (!S_ISREG(st.st_mode)) throw ImageError(path, "not a regular file");
  // One byte more than the size, so that the read seeing the end needs no reallocation.
  std::vector<unsigned char> bytes(static_cast<size_t>(st.st_size) + 1);
  size_t got = 0;
  while (true) {
    if (got == bytes.size()) bytes.resize(got + 4096 + got / 2);  // the file grew while being read
    const ssize_t n = ::read(fd, bytes.data() + got, bytes.size() - got);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw ImageError(path, std::string("cannot read image file (") + std::strerror(errno) + ")");
    }
    if (n == 0) break;
    got += static_cast<size_t>(n);
  }
  bytes.resize(got);
  return bytes;
}

bool startsWith(const std::vector<unsigned char>& b, const unsigned char* sig, size_t n) {
  return b.size() >= n && std::memcmp(b.data(), sig, n) == 0;
}

void checkSize(const std::string& path, const char* format, uint64_t width, uint64_t height) {
  if (width == 0 || height == 0 || width > kMaxSide || height > kMaxSide || width * height > kMaxPixels)
    throw ImageError(path, std::string("cannot decode ") + format + ": image size " + std::to_string(width) + "x" +
                               std::to_string(height) + " is outside 1..2^20 per side and 2^30 pixels in all");
}

// cv::Mat's allocator throws cv::Exception when memory runs out; callers expect an ImageError.
cv::Mat allocate(const std::string& path, const char* format, int rows, int cols, int type) {
  try {
    return cv::Mat(rows, cols, type);
  } catch (const cv::Exception&) {
    throw ImageError(path, std::string("cannot decode ") + format + ": out of memory for a " + std::to_string(cols) +
                               "x" + std::to_string(rows) + " image");
  }
}

// ---- PNG reading -----------------------------------------------------------------------------------

// Everything libpng's callbacks and the setjmp stages touch: plain data only.
struct PngReadContext {
  png_structp png = nullptr;
  png_infop info = nullptr;
  const unsigned char* data = nullptr;
  size_t size = 0;
  size_t pos = 0;
  char message[256] = {};
};

void pngError(png_structp png, png_const_charp msg) {
  auto* c = static_cast<PngReadContext*>(png_get_error_ptr(png));
  std::snprintf(c->message, sizeof(c->message), "%s", msg ? msg : "unknown libpng error");
  png_longjmp(png, 1);  // returning would let libpng print to stderr before it jumps itself
}

// Warnings concern ancillary chunks (the pixels are intact): not printed, not an error.
void pngWarning(png_structp, png_const_charp) {}

void pngReadFromMemory(png_structp png, png_bytep out, png_size_t n) {
  auto* c = static_cast<PngReadContext*>(png_get_io_ptr(png));
  if (n > c->size - c->pos) {
    std::snprintf(c->message, sizeof(c->message), "the file is truncated (it ends at byte %zu)", c->size);
    png_longjmp(png, 1);
  }
  std::memcpy(out, c->data + c->pos, n);
  c->pos += n;
}

struct PngHeader {
  png_uint_32 width = 0, height = 0;
  int bit_depth = 0, color_type = 0;
  int num_trans = 0;
};

// setjmp stage: no object with a destructor in this frame.
bool pngReadHeader(PngReadContext* c, PngHeader* h) {
  if (setjmp(png_jmpbuf(c->png))) return false;
  png_set_read_fn(c->png, c, pngReadFromMemory);
  png_read_info(c->png, c->info);
  png_get_IHDR(c->png, c->info, &h->width, &h->height, &h->bit_depth, &h->color_type, nullptr, nullptr, nullptr);
  png_bytep trans = nullptr;
  png_color_16p trans_values = nullptr;
  h->num_trans = 0;
  png_get_tRNS(c->png, c->info, &trans, &h->num_trans, &trans_values);
  return true;
}

// setjmp stage: the transformations OpenCV's PngDecoder::readData sets for IMREAD_UNCHANGED, in its order,
// then the rows. `rows` point into a cv::Mat the caller owns, of row_bytes bytes each.
bool pngReadPixels(PngReadContext* c, const PngHeader* h, int channels, size_t row_bytes, png_bytepp rows) {
  if (setjmp(png_jmpbuf(c->png))) return false;
  if (h->bit_depth == 16 && kLittleEndian) png_set_swap(c->png);  // file: big-endian
  if (channels < 4)
    png_set_strip_alpha(c->png);  // no alpha channel requested: a grey tRNS is dropped
  else
    png_set_tRNS_to_alpha(c->png);
  if (h->color_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(c->png);
  if ((h->color_type & PNG_COLOR_MASK_COLOR) == 0 && h->bit_depth < 8) png_set_expand_gray_1_2_4_to_8(c->png);
  if ((h->color_type & PNG_COLOR_MASK_COLOR) != 0 && channels > 1)
    png_set_bgr(c->png);
  else if (channels > 1)
    png_set_gray_to_rgb(c->png);  // grey + alpha -> BGRA
  // (OpenCV also calls png_set_rgb_to_gray here for one channel; the source is then grey and it does nothing.)
  png_set_interlace_handling(c->png);
  png_read_update_info(c->png, c->info);
  if (png_get_rowbytes(c->png, c->info) != row_bytes) {
    std::snprintf(c->message, sizeof(c->message), "unexpected row size %zu bytes after conversion (expected %zu)",
                  static_cast<size_t>(png_get_rowbytes(c->png, c->info)), row_bytes);
    return false;
  }
  png_read_image(c->png, rows);
  png_read_end(c->png, nullptr);
  return true;
}

class PngReader {
 public:
  PngReader(const unsigned char* data, size_t size) {
    c_.data = data;
    c_.size = size;
    c_.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &c_, pngError, pngWarning);
    if (c_.png) c_.info = png_create_info_struct(c_.png);
  }
  ~PngReader() {
    if (c_.png) png_destroy_read_struct(&c_.png, c_.info ? &c_.info : nullptr, nullptr);
  }
  PngReader(const PngReader&) = delete;
  PngReader& operator=(const PngReader&) = delete;
  PngReadContext* context() { return &c_; }
  bool ok() const { return c_.png && c_.info; }

 private:
  PngReadContext c_;
};

cv::Mat decodePng(const std::string& path, const std::vector<unsigned char>& bytes) {
  PngReader reader(bytes.data(), bytes.size());
  PngReadContext* c = reader.context();
  if (!reader.ok()) throw ImageError(path, "cannot decode PNG: libpng could not start (out of memory?)");
  PngHeader h;
  if (!pngReadHeader(c, &h)) throw ImageError(path, std::string("cannot decode PNG: ") + c->message);
  checkSize(path, "PNG", h.width, h.height);
  // The type OpenCV's PngDecoder::readHeader gives (IMREAD_UNCHANGED keeps it).
  int channels = 1;
  switch (h.color_type) {
    case PNG_COLOR_TYPE_RGB:
    case PNG_COLOR_TYPE_PALETTE:
      channels = h.num_trans > 0 ? 4 : 3;
      break;
    case PNG_COLOR_TYPE_GRAY_ALPHA:
    case PNG_COLOR_TYPE_RGB_ALPHA:
      channels = 4;
      break;
    default:
      channels = 1;
  }
  const int depth = h.bit_depth == 16 ? CV_16U : CV_8U;
  cv::Mat img =
      allocate(path, "PNG", static_cast<int>(h.height), static_cast<int>(h.width), CV_MAKETYPE(depth, channels));
  std::vector<png_bytep> rows(img.rows);
  for (int y = 0; y < img.rows; ++y) rows[y] = img.ptr<png_byte>(y);
  const size_t row_bytes = static_cast<size_t>(img.cols) * img.elemSize();
  if (!pngReadPixels(c, &h, channels, row_bytes, rows.data()))
    throw ImageError(path, std::string("cannot decode PNG: ") + c->message);
  return img;
}

// ---- JPEG reading ----------------------------------------------------------------------------------

struct JpegErrorManager {
  jpeg_error_mgr mgr;  // first member: libjpeg hands back &mgr as cinfo->err
  jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

[[noreturn]] void jpegErrorExit(j_common_ptr cinfo) {
  auto* e = reinterpret_cast<JpegErrorManager*>(cinfo->err);
  (*cinfo->err->format_message)(cinfo, e->message);
  std::longjmp(e->jump, 1);
}

// Warnings (level -1) that mean pixels are missing or wrong are errors; libjpeg would go on and fill
// the rest of the image with grey. The others (extra bytes between markers, an unknown JFIF revision or
// Adobe transform code, a bad ICC marker) leave the pixels intact and are ignored. Trace messages
// (level >= 0) are ignored. Nothing is printed.
void jpegEmitMessage(j_common_ptr cinfo, int level) {
  if (level >= 0) return;
  switch (cinfo->err->msg_code) {
    case JWRN_JPEG_EOF:
    case JWRN_HIT_MARKER:
    case JWRN_HUFF_BAD_CODE:
    case JWRN_ARITH_BAD_CODE:
    case JWRN_MUST_RESYNC:
    case JWRN_NOT_SEQUENTIAL:
    case JWRN_BOGUS_PROGRESSION:
      jpegErrorExit(cinfo);
    default:
      cinfo->err->num_warnings++;
  }
}

struct JpegReadContext {  // no member initialisers: JpegReader value-initialises it (all zero)
  jpeg_decompress_struct cinfo;
  JpegErrorManager err;
  bool created;  // jpeg_create_decompress was called: jpeg_destroy_decompress is due
};

// setjmp stage: no object with a destructor in this frame.
bool jpegReadHeader(JpegReadContext* c, const unsigned char* data, size_t size) {
  c->cinfo.err = jpeg_std_error(&c->err.mgr);
  c->err.mgr.error_exit = jpegErrorExit;
  c->err.mgr.emit_message = jpegEmitMessage;
  c->err.message[0] = '\0';
  if (setjmp(c->err.jump)) return false;
  jpeg_create_decompress(&c->cinfo);
  c->created = true;
  jpeg_mem_src(&c->cinfo, data, static_cast<unsigned long>(size));
  jpeg_read_header(&c->cinfo, TRUE);
  return true;
}

// setjmp stage: decodes into `data` (rows of `step` bytes) as grey or BGR, as OpenCV's JpegDecoder.
bool jpegReadPixels(JpegReadContext* c, bool colour, unsigned char* data, size_t step) {
  if (setjmp(c->err.jump)) return false;
  j_decompress_ptr cinfo = &c->cinfo;
  cinfo->out_color_space = colour ? JCS_EXT_BGR : JCS_GRAYSCALE;
  cinfo->out_color_components = colour ? 3 : 1;
  jpeg_start_decompress(cinfo);
  while (cinfo->output_scanline < cinfo->output_height) {
    JSAMPROW row = data + static_cast<size_t>(cinfo->output_scanline) * step;
    if (jpeg_read_scanlines(cinfo, &row, 1) != 1) {
      std::snprintf(c->err.message, sizeof(c->err.message), "no data for row %u", cinfo->output_scanline);
      return false;
    }
  }
  jpeg_finish_decompress(cinfo);
  return true;
}

class JpegReader {
 public:
  JpegReader() : c_() {}
  ~JpegReader() {
    if (c_.created) jpeg_destroy_decompress(&c_.cinfo);
  }
  JpegReader(const JpegReader&) = delete;
  JpegReader& operator=(const JpegReader&) = delete;
  JpegReadContext* context() { return &c_; }

 private:
  JpegReadContext c_;
};

cv::Mat decodeJpeg(const std::string& path, const std::vector<unsigned char>& bytes) {
  JpegReader reader;
  JpegReadContext* c = reader.context();
  if (!jpegReadHeader(c, bytes.data(), bytes.size()))
    throw ImageError(path, std::string("cannot decode JPEG: ") + c->err.message);
  const jpeg_decompress_struct& ci = c->cinfo;
  if (ci.jpeg_color_space == JCS_CMYK || ci.jpeg_color_space == JCS_YCCK || ci.num_components == 4)
    throw ImageError(path, "cannot decode JPEG: CMYK/YCCK JPEG is not supported (expected grey or colour)");
  checkSize(path, "JPEG", ci.image_width, ci.image_height);
  const bool colour = ci.num_components > 1;  // OpenCV: CV_8UC3 for any multi-component JPEG
  cv::Mat img = allocate(path, "JPEG", static_cast<int>(ci.image_height), static_cast<int>(ci.image_width),
                         colour ? CV_8UC3 : CV_8UC1);
  if (!jpegReadPixels(c, colour, img.data, img.step[0]))
    throw ImageError(path, std::string("cannot decode JPEG: ") + c->err.message);
  return img;
}

// ---- PNG writing -----------------------------------------------------------------------------------

struct PngWriteContext {
  png_structp png = nullptr;
  png_infop info = nullptr;
  std::vector<unsigned char>* out = nullptr;
  char message[256] = {};
};

void pngWriteError(png_structp png, png_const_charp msg) {
  auto* c = static_cast<PngWriteContext*>(png_get_error_ptr(png));
  std::snprintf(c->message, sizeof(c->message), "%s", msg ? msg : "unknown libpng error");
  png_longjmp(png, 1);
}

void pngWriteToMemory(png_structp png, png_bytep data, png_size_t n) {
  auto* c = static_cast<PngWriteContext*>(png_get_io_ptr(png));
  bool ok = true;
  try {
    c->out->insert(c->out->end(), data, data + n);
  } catch (...) {  // bad_alloc must not unwind through libpng
    ok = false;
  }
  if (!ok) png_error(png, "out of memory");
}

void pngFlush(png_structp) {}

struct PngWriteSpec {
  png_uint_32 width = 0, height = 0;
  int bit_depth = 8, color_type = PNG_COLOR_TYPE_GRAY;
  int compression = 1;
};

// setjmp stage: OpenCV's PngEncoder settings for IMWRITE_PNG_COMPRESSION (level, default strategy,
// libpng's default filters), samples given in BGR(A) order and host byte order.
bool pngEncode(PngWriteContext* c, const PngWriteSpec* s, png_bytepp rows) {
  if (setjmp(png_jmpbuf(c->png))) return false;
  png_set_write_fn(c->png, c, pngWriteToMemory, pngFlush);
  png_set_compression_level(c->png, s->compression);
  png_set_compression_strategy(c->png, Z_DEFAULT_STRATEGY);
  png_set_IHDR(c->png, c->info, s->width, s->height, s->bit_depth, s->color_type, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(c->png, c->info);
  png_set_bgr(c->png);
  if (s->bit_depth == 16 && kLittleEndian) png_set_swap(c->png);
  png_write_image(c->png, rows);
  png_write_end(c->png, c->info);
  return true;
}

class PngWriter {
 public:
  explicit PngWriter(std::vector<unsigned char>* out) {
    c_.out = out;
    c_.png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &c_, pngWriteError, pngWarning);
    if (c_.png) c_.info = png_create_info_struct(c_.png);
  }
  ~PngWriter() {
    if (c_.png) png_destroy_write_struct(&c_.png, c_.info ? &c_.info : nullptr);
  }
  PngWriter(const PngWriter&) = delete;
  PngWriter& operator=(const PngWriter&) = delete;
  PngWriteContext* context() { return &c_; }
  bool ok() const { return c_.png && c_.info; }

 private:
  PngWriteContext c_;
};

}  // namespace

bool hasPngSignature(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char buf[sizeof(kPngSignature)] = {};
  return in.read(reinterpret_cast<char*>(buf), sizeof(buf)) && std::memcmp(buf, kPngSignature, sizeof(buf)) == 0;
}

cv::Mat readImage(const std::string& path) {
  const std::vector<unsigned char> bytes = readFileBytes(path);
  if (bytes.empty()) throw ImageError(path, "image file is empty");
  if (startsWith(bytes, kPngSignature, sizeof(kPngSignature))) return decodePng(path, bytes);
  if (startsWith(bytes, kJpegStart, sizeof(kJpegStart))) return decodeJpeg(path, bytes);
  throw ImageError(path, "not a PNG or JPEG file (it starts with neither the PNG signature nor the JPEG marker "
                         "FF D8 FF); supported image formats: PNG (any), JPEG (grey or colour)");
}

void writePng(const std::string& path, const cv::Mat& img, int compression) {
  const int type = img.type();
  if (type != CV_8UC1 && type != CV_16UC1 && type != CV_8UC3 && type != CV_8UC4)
    throw Error(path + ": cannot write PNG: unsupported image type " + cv::typeToString(type) +
                " (expected CV_8UC1, CV_16UC1, CV_8UC3 or CV_8UC4)");
  if (img.empty()) throw Error(path + ": cannot write PNG: the image is empty");
  if (compression < 0 || compression > 9)
    throw Error(path + ": cannot write PNG: compression level " + std::to_string(compression) + " outside 0..9");
  PngWriteSpec s;
  s.width = static_cast<png_uint_32>(img.cols);
  s.height = static_cast<png_uint_32>(img.rows);
  s.bit_depth = img.depth() == CV_16U ? 16 : 8;
  s.color_type = img.channels() == 1 ? PNG_COLOR_TYPE_GRAY
                 : img.channels() == 3 ? PNG_COLOR_TYPE_RGB
                                       : PNG_COLOR_TYPE_RGB_ALPHA;
  s.compression = compression;
  std::vector<png_bytep> rows(img.rows);
  for (int y = 0; y < img.rows; ++y) rows[y] = const_cast<png_bytep>(img.ptr<png_byte>(y));  // libpng copies rows
  std::vector<unsigned char> bytes;
  bytes.reserve(img.total() * img.elemSize() / 2 + 1024);
  {
    PngWriter writer(&bytes);
    if (!writer.ok()) throw Error(path + ": cannot write PNG: libpng could not start (out of memory?)");
    if (!pngEncode(writer.context(), &s, rows.data()))
      throw Error(path + ": cannot write PNG: " + writer.context()->message);
  }
  writeFileAtomic(
      path, [&](std::ostream& o) { o.write(reinterpret_cast<const char*>(bytes.data()), bytes.size()); }, "PNG",
      /*binary=*/true);
}

}  // namespace rsvio::io
