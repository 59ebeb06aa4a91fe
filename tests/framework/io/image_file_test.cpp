// rsvio/io/image_file.h against OpenCV's imgcodecs, the independent reference (linked to the tests only):
// files written by cv::imwrite (or crafted here with libpng/libjpeg for what OpenCV does not write) must
// decode to exactly cv::imread(path, IMREAD_UNCHANGED); files from writePng must read back exactly with
// cv::imread; bad files must give an ImageError naming the file, never a crash.
#include <gtest/gtest.h>
#include <unistd.h>

#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <vector>

// jpeglib.h needs <cstdio> before it.
#include <jpeglib.h>
#include <png.h>
#include <zlib.h>

#include "rsvio/io/image_file.h"

namespace rsvio::io {
namespace {
namespace fs = std::filesystem;

class ImageFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("rsvio_image_file_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

std::string bytesOf(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void writeBytes(const std::string& p, const std::string& b) { std::ofstream(p, std::ios::binary) << b; }

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const ImageError& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("not an ImageError: ") + e.what();
  }
  return "no error";
}

// Exact equality: type, size and every byte of every row.
::testing::AssertionResult same(const cv::Mat& a, const cv::Mat& b) {
  if (a.type() != b.type())
    return ::testing::AssertionFailure() << "types " << cv::typeToString(a.type()) << " vs "
                                         << cv::typeToString(b.type());
  if (a.size() != b.size()) return ::testing::AssertionFailure() << "sizes " << a.size() << " vs " << b.size();
  for (int y = 0; y < a.rows; ++y)
    for (size_t x = 0; x < a.cols * a.elemSize(); ++x)
      if (a.ptr<uchar>(y)[x] != b.ptr<uchar>(y)[x])
        return ::testing::AssertionFailure() << "byte " << x << " of row " << y << ": " << int(a.ptr<uchar>(y)[x])
                                             << " vs " << int(b.ptr<uchar>(y)[x]);
  return ::testing::AssertionSuccess();
}

cv::Mat randomImage(int rows, int cols, int type, unsigned seed) {
  cv::Mat m(rows, cols, type);
  cv::theRNG().state = seed;
  cv::randu(m, cv::Scalar::all(0), cv::Scalar::all(CV_MAT_DEPTH(type) == CV_16U ? 65536 : 256));
  return m;
}

// A smooth picture with a little noise (what a camera gives; JPEG's chroma upsampling has work to do).
cv::Mat photo(int rows, int cols, int channels) {
  cv::Mat m(rows, cols, CV_8UC(channels));
  std::mt19937 rng(7);
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < cols; ++x)
      for (int c = 0; c < channels; ++c)
        m.ptr<uchar>(y)[x * channels + c] = cv::saturate_cast<uchar>(
            128 + 90 * std::sin(0.13 * x * (c + 1) + 0.07 * y) + 20 * std::cos(0.3 * y - c) + int(rng() % 9) - 4);
  return m;
}

const std::vector<int> kWriteTypes = {CV_8UC1, CV_16UC1, CV_8UC3, CV_8UC4};

// ---- round trips and OpenCV cross-checks -----------------------------------------------------------

TEST_F(ImageFile, WritePngThenReadImageGivesTheSamePixels) {
  for (int type : kWriteTypes)
    for (int level : {0, 1, 6, 9}) {
      const cv::Mat img = randomImage(23, 37, type, 11 + level);
      const std::string p = path("rt.png");
      writePng(p, img, level);
      EXPECT_TRUE(same(readImage(p), img)) << cv::typeToString(type) << " level " << level;
    }
}

TEST_F(ImageFile, WritePngOfARegionOfInterestWritesOnlyTheRegion) {
  const cv::Mat big = randomImage(40, 50, CV_16UC1, 3);
  const cv::Mat roi = big(cv::Rect(7, 5, 21, 13));
  ASSERT_FALSE(roi.isContinuous());
  writePng(path("roi.png"), roi, 1);
  EXPECT_TRUE(same(readImage(path("roi.png")), roi));
}

TEST_F(ImageFile, OpenCvWritesReadImageReadsWhatImreadReads) {
  // 16-bit colour too (OpenCV writes it): read as BGR/BGRA in host byte order.
  for (int type : {CV_8UC1, CV_16UC1, CV_8UC3, CV_8UC4, CV_16UC3, CV_16UC4})
    for (int level : {1, 9}) {
      const cv::Mat img = randomImage(19, 31, type, 5);
      const std::string p = path("cv.png");
      ASSERT_TRUE(cv::imwrite(p, img, {cv::IMWRITE_PNG_COMPRESSION, level}));
      const cv::Mat ours = readImage(p);
      EXPECT_TRUE(same(ours, cv::imread(p, cv::IMREAD_UNCHANGED))) << cv::typeToString(type);
      EXPECT_TRUE(same(ours, img)) << cv::typeToString(type);
    }
}

TEST_F(ImageFile, SixteenBitSamplesComeBackInHostOrder) {
  cv::Mat img(2, 3, CV_16UC1);
  const uint16_t v[6] = {0x0102, 0xFF00, 0x00FF, 1, 256, 65535};
  std::memcpy(img.data, v, sizeof(v));
  ASSERT_TRUE(cv::imwrite(path("s.png"), img));
  const cv::Mat ours = readImage(path("s.png"));
  EXPECT_TRUE(same(ours, cv::imread(path("s.png"), cv::IMREAD_UNCHANGED)));
  EXPECT_EQ(ours.at<uint16_t>(0, 0), 0x0102);
  EXPECT_EQ(ours.at<uint16_t>(0, 1), 0xFF00);
  // In the file: big-endian.
  writePng(path("w.png"), img, 1);
  EXPECT_TRUE(same(cv::imread(path("w.png"), cv::IMREAD_UNCHANGED), img));
}

TEST_F(ImageFile, OpenCvBilevelPngIsOneBitAndReadsAsZeroOr255) {
  cv::Mat img = randomImage(17, 29, CV_8UC1, 9);
  cv::threshold(img, img, 127, 255, cv::THRESH_BINARY);
  ASSERT_TRUE(cv::imwrite(path("bi.png"), img, {cv::IMWRITE_PNG_BILEVEL, 1}));
  EXPECT_EQ(static_cast<unsigned char>(bytesOf(path("bi.png"))[24]), 1) << "IHDR bit depth";
  const cv::Mat ours = readImage(path("bi.png"));
  EXPECT_TRUE(same(ours, cv::imread(path("bi.png"), cv::IMREAD_UNCHANGED)));
  EXPECT_TRUE(same(ours, img));
}

TEST_F(ImageFile, WritePngReadsBackWithImread) {
  for (int type : kWriteTypes) {
    const cv::Mat img = randomImage(21, 33, type, 17);
    writePng(path("ours.png"), img, 3);
    EXPECT_TRUE(same(cv::imread(path("ours.png"), cv::IMREAD_UNCHANGED), img)) << cv::typeToString(type);
  }
}

TEST_F(ImageFile, WritePngHasTheBytesOfImwriteWithTheSameCompression) {
  for (int type : kWriteTypes)
    for (int level : {0, 1, 4, 9}) {
      const cv::Mat img = type == CV_16UC1 ? randomImage(30, 40, type, 2) : photo(30, 40, CV_MAT_CN(type));
      writePng(path("ours.png"), img, level);
      ASSERT_TRUE(cv::imwrite(path("cv.png"), img, {cv::IMWRITE_PNG_COMPRESSION, level}));
      EXPECT_EQ(bytesOf(path("ours.png")), bytesOf(path("cv.png"))) << cv::typeToString(type) << " level " << level;
    }
}

// ---- PNG kinds OpenCV does not write: crafted with libpng ----------------------------------------

struct RawPng {
  png_uint_32 width = 0, height = 0;
  int bit_depth = 8, color_type = PNG_COLOR_TYPE_GRAY;
  bool interlace = false;
  std::vector<png_color> palette;
  std::vector<png_byte> palette_alpha;  // tRNS of a palette image
  bool has_key = false;                 // tRNS of a grey/RGB image: this colour is transparent
  png_color_16 key{};
  double gamma = 0;                     // gAMA chunk when > 0
  std::vector<std::vector<png_byte>> rows;  // as stored: packed below 8 bits, 16-bit big-endian
};

// setjmp frame with plain data only (libpng's default error handler longjmps here).
bool writeRawPngFile(FILE* f, const RawPng* p, png_bytepp rows) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!info) return false;
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_init_io(png, f);
  png_set_IHDR(png, info, p->width, p->height, p->bit_depth, p->color_type,
               p->interlace ? PNG_INTERLACE_ADAM7 : PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  if (!p->palette.empty()) png_set_PLTE(png, info, p->palette.data(), static_cast<int>(p->palette.size()));
  if (!p->palette_alpha.empty())
    png_set_tRNS(png, info, p->palette_alpha.data(), static_cast<int>(p->palette_alpha.size()), nullptr);
  if (p->has_key) png_set_tRNS(png, info, nullptr, 1, const_cast<png_color_16p>(&p->key));
  if (p->gamma > 0) png_set_gAMA(png, info, p->gamma);
  png_write_info(png, info);
  png_write_image(png, rows);
  png_write_end(png, info);
  png_destroy_write_struct(&png, &info);
  return true;
}

void writeRawPng(const std::string& path, RawPng& p) {
  std::vector<png_bytep> rows;
  for (auto& r : p.rows) rows.push_back(r.data());
  FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  const bool ok = writeRawPngFile(f, &p, rows.data());
  std::fclose(f);
  ASSERT_TRUE(ok) << path;
}

// Rows of `samples_per_row` values of `bits` bits each (values taken from rng), packed as PNG stores them.
std::vector<std::vector<png_byte>> packedRows(int height, int samples_per_row, int bits, unsigned max_value,
                                              std::vector<std::vector<unsigned>>* values, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<std::vector<png_byte>> rows(height);
  values->assign(height, {});
  for (int y = 0; y < height; ++y) {
    std::vector<png_byte>& r = rows[y];
    r.assign((static_cast<size_t>(samples_per_row) * bits + 7) / 8, 0);
    for (int i = 0; i < samples_per_row; ++i) {
      const unsigned v = rng() % (max_value + 1);
      (*values)[y].push_back(v);
      if (bits == 16) {
        r[2 * i] = static_cast<png_byte>(v >> 8);
        r[2 * i + 1] = static_cast<png_byte>(v & 0xFF);
      } else if (bits == 8) {
        r[i] = static_cast<png_byte>(v);
      } else {
        const int bit = i * bits;
        r[bit / 8] |= static_cast<png_byte>(v << (8 - bits - bit % 8));
      }
    }
  }
  return rows;
}

struct Crafted {
  const char* name;
  int bit_depth, color_type;
  bool palette_alpha, key, interlace;
  double gamma;
  int expected_type;
};

TEST_F(ImageFile, CraftedPngKindsReadAsImreadReadsThem) {
  const std::vector<Crafted> kinds = {
      {"grey1", 1, PNG_COLOR_TYPE_GRAY, false, false, false, 0, CV_8UC1},
      {"grey2", 2, PNG_COLOR_TYPE_GRAY, false, false, false, 0, CV_8UC1},
      {"grey4", 4, PNG_COLOR_TYPE_GRAY, false, false, false, 0, CV_8UC1},
      {"grey4_interlaced", 4, PNG_COLOR_TYPE_GRAY, false, false, true, 0, CV_8UC1},
      {"grey8_key", 8, PNG_COLOR_TYPE_GRAY, false, true, false, 0, CV_8UC1},
      {"grey8_gamma", 8, PNG_COLOR_TYPE_GRAY, false, false, false, 0.45455, CV_8UC1},
      {"grey16_gamma", 16, PNG_COLOR_TYPE_GRAY, false, false, false, 1.0 / 2.2, CV_16UC1},
      {"grey16_interlaced", 16, PNG_COLOR_TYPE_GRAY, false, false, true, 0, CV_16UC1},
      {"grey_alpha8", 8, PNG_COLOR_TYPE_GRAY_ALPHA, false, false, false, 0, CV_8UC4},
      {"grey_alpha16", 16, PNG_COLOR_TYPE_GRAY_ALPHA, false, false, false, 0, CV_16UC4},
      {"palette1", 1, PNG_COLOR_TYPE_PALETTE, false, false, false, 0, CV_8UC3},
      {"palette2", 2, PNG_COLOR_TYPE_PALETTE, false, false, false, 0, CV_8UC3},
      {"palette4", 4, PNG_COLOR_TYPE_PALETTE, false, false, false, 0, CV_8UC3},
      {"palette8", 8, PNG_COLOR_TYPE_PALETTE, false, false, false, 0, CV_8UC3},
      {"palette8_alpha", 8, PNG_COLOR_TYPE_PALETTE, true, false, false, 0, CV_8UC4},
      {"palette4_alpha_interlaced", 4, PNG_COLOR_TYPE_PALETTE, true, false, true, 0, CV_8UC4},
      {"rgb8_key", 8, PNG_COLOR_TYPE_RGB, false, true, false, 0, CV_8UC4},
      {"rgb16_key", 16, PNG_COLOR_TYPE_RGB, false, true, false, 0, CV_16UC4},
      {"rgb8_interlaced_gamma", 8, PNG_COLOR_TYPE_RGB, false, false, true, 0.45455, CV_8UC3},
      {"rgba16_interlaced", 16, PNG_COLOR_TYPE_RGB_ALPHA, false, false, true, 0, CV_16UC4},
  };
  for (const Crafted& k : kinds) {
    SCOPED_TRACE(k.name);
    RawPng p;
    p.width = 27;
    p.height = 11;
    p.bit_depth = k.bit_depth;
    p.color_type = k.color_type;
    p.interlace = k.interlace;
    p.gamma = k.gamma;
    const int channels = k.color_type == PNG_COLOR_TYPE_RGB         ? 3
                         : k.color_type == PNG_COLOR_TYPE_RGB_ALPHA  ? 4
                         : k.color_type == PNG_COLOR_TYPE_GRAY_ALPHA ? 2
                                                                     : 1;
    const unsigned max_value = (1u << k.bit_depth) - 1;
    std::vector<std::vector<unsigned>> values;
    p.rows = packedRows(11, 27 * channels, k.bit_depth, max_value, &values, 100 + k.bit_depth);
    if (k.color_type == PNG_COLOR_TYPE_PALETTE) {
      for (unsigned i = 0; i <= max_value; ++i)
        p.palette.push_back({static_cast<png_byte>(i * 37 % 256), static_cast<png_byte>(255 - i),
                             static_cast<png_byte>(i * 91 % 256)});
      if (k.palette_alpha)
        for (unsigned i = 0; i <= max_value && i < 5; ++i) p.palette_alpha.push_back(static_cast<png_byte>(i * 50));
    }
    if (k.key) {  // the colour of the first pixel is the transparent one
      p.has_key = true;
      p.key.gray = static_cast<png_uint_16>(values[0][0]);
      if (channels == 3) {
        p.key.red = static_cast<png_uint_16>(values[0][0]);
        p.key.green = static_cast<png_uint_16>(values[0][1]);
        p.key.blue = static_cast<png_uint_16>(values[0][2]);
      }
    }
    const std::string f = path(std::string(k.name) + ".png");
    writeRawPng(f, p);
    const cv::Mat ours = readImage(f);
    EXPECT_EQ(ours.type(), k.expected_type) << cv::typeToString(ours.type());
    EXPECT_TRUE(same(ours, cv::imread(f, cv::IMREAD_UNCHANGED)));
    // A few values worked out by hand, independently of OpenCV.
    if (k.color_type == PNG_COLOR_TYPE_GRAY && k.bit_depth < 8)
      EXPECT_EQ(ours.at<uchar>(3, 4), values[3][4] * 255 / max_value);
    if (k.color_type == PNG_COLOR_TYPE_PALETTE) {
      const png_color c = p.palette[values[2][5]];
      const uchar* px = ours.ptr<uchar>(2) + 5 * ours.channels();
      EXPECT_EQ(px[0], c.blue);
      EXPECT_EQ(px[1], c.green);
      EXPECT_EQ(px[2], c.red);
    }
    if (k.color_type == PNG_COLOR_TYPE_GRAY_ALPHA && k.bit_depth == 8) {
      const cv::Vec4b px = ours.at<cv::Vec4b>(1, 2);
      EXPECT_EQ(px, cv::Vec4b(values[1][4], values[1][4], values[1][4], values[1][5]));
    }
    if (k.key && channels == 3 && k.bit_depth == 8) {
      EXPECT_EQ(ours.at<cv::Vec4b>(0, 0), cv::Vec4b(values[0][2], values[0][1], values[0][0], 0));
    }
  }
}

// ---- JPEG ---------------------------------------------------------------------------------------

// setjmp frame with plain data only: a JPEG with the given chroma sampling (h, v of the first component).
bool writeJpegFile(FILE* f, const cv::Mat* rgb_or_grey, int h_samp, int v_samp, bool progressive) {
  jpeg_compress_struct ci;
  jpeg_error_mgr err;
  ci.err = jpeg_std_error(&err);
  jpeg_create_compress(&ci);
  jpeg_stdio_dest(&ci, f);
  ci.image_width = static_cast<JDIMENSION>(rgb_or_grey->cols);
  ci.image_height = static_cast<JDIMENSION>(rgb_or_grey->rows);
  ci.input_components = rgb_or_grey->channels();
  ci.in_color_space = rgb_or_grey->channels() == 3 ? JCS_RGB : JCS_GRAYSCALE;
  jpeg_set_defaults(&ci);
  jpeg_set_quality(&ci, 85, TRUE);
  ci.comp_info[0].h_samp_factor = h_samp;
  ci.comp_info[0].v_samp_factor = v_samp;
  if (progressive) jpeg_simple_progression(&ci);
  jpeg_start_compress(&ci, TRUE);
  while (ci.next_scanline < ci.image_height) {
    JSAMPROW row = const_cast<JSAMPROW>(rgb_or_grey->ptr<JSAMPLE>(static_cast<int>(ci.next_scanline)));
    jpeg_write_scanlines(&ci, &row, 1);
  }
  jpeg_finish_compress(&ci);
  jpeg_destroy_compress(&ci);
  return true;
}

TEST_F(ImageFile, JpegFromImwriteReadsAsImreadReadsIt) {
  for (int channels : {1, 3})
    for (int quality : {50, 95})
      for (int progressive : {0, 1}) {
        const cv::Mat img = photo(45, 61, channels);  // odd sizes: partial blocks and chroma edges
        const std::string p = path("cv.jpg");
        ASSERT_TRUE(
            cv::imwrite(p, img, {cv::IMWRITE_JPEG_QUALITY, quality, cv::IMWRITE_JPEG_PROGRESSIVE, progressive}));
        const cv::Mat ours = readImage(p);
        EXPECT_EQ(ours.type(), channels == 1 ? CV_8UC1 : CV_8UC3);
        EXPECT_TRUE(same(ours, cv::imread(p, cv::IMREAD_UNCHANGED)))
            << channels << " channels, quality " << quality << ", progressive " << progressive;
        EXPECT_LT(cv::norm(ours, img, cv::NORM_L1) / img.total() / channels, 12.0) << "BGR order";
      }
}

TEST_F(ImageFile, JpegWithOtherChromaSamplingReadsAsImreadReadsIt) {
  const cv::Mat bgr = photo(37, 50, 3);
  cv::Mat rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  for (auto [h, v] : {std::pair{1, 1}, std::pair{2, 1}, std::pair{1, 2}, std::pair{2, 2}}) {
    const std::string p = path("s.jpg");
    FILE* f = std::fopen(p.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    writeJpegFile(f, &rgb, h, v, false);
    std::fclose(f);
    const cv::Mat ours = readImage(p);
    EXPECT_TRUE(same(ours, cv::imread(p, cv::IMREAD_UNCHANGED))) << h << "x" << v;
    EXPECT_LT(cv::norm(ours, bgr, cv::NORM_L1) / bgr.total() / 3, 12.0) << "BGR order";
  }
}

// setjmp frame with plain data only: a 4-component Adobe CMYK JPEG.
bool writeCmykJpegFile(FILE* f, const unsigned char* cmyk, int width, int height) {
  jpeg_compress_struct ci;
  jpeg_error_mgr err;
  ci.err = jpeg_std_error(&err);
  jpeg_create_compress(&ci);
  jpeg_stdio_dest(&ci, f);
  ci.image_width = static_cast<JDIMENSION>(width);
  ci.image_height = static_cast<JDIMENSION>(height);
  ci.input_components = 4;
  ci.in_color_space = JCS_CMYK;
  jpeg_set_defaults(&ci);
  jpeg_start_compress(&ci, TRUE);
  while (ci.next_scanline < ci.image_height) {
    JSAMPROW row = const_cast<JSAMPROW>(cmyk + static_cast<size_t>(ci.next_scanline) * width * 4);
    jpeg_write_scanlines(&ci, &row, 1);
  }
  jpeg_finish_compress(&ci);
  jpeg_destroy_compress(&ci);
  return true;
}

TEST_F(ImageFile, CmykJpegIsRefusedWithAReason) {
  const std::vector<unsigned char> cmyk(16 * 8 * 4, 100);
  const std::string p = path("cmyk.jpg");
  FILE* f = std::fopen(p.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  writeCmykJpegFile(f, cmyk.data(), 16, 8);
  std::fclose(f);
  ASSERT_EQ(cv::imread(p, cv::IMREAD_UNCHANGED).type(), CV_8UC3);  // OpenCV converts it to BGR
  EXPECT_EQ(errorOf([&] { readImage(p); }),
            p + ": cannot decode JPEG: CMYK/YCCK JPEG is not supported (expected grey or colour)");
}

TEST_F(ImageFile, FormatComesFromTheSignatureNotTheName) {
  const cv::Mat img = photo(10, 12, 1);
  ASSERT_TRUE(cv::imwrite(path("a.png"), img));
  ASSERT_TRUE(cv::imwrite(path("b.jpg"), img));
  fs::rename(path("a.png"), path("a.jpg"));
  fs::rename(path("b.jpg"), path("b.png"));
  EXPECT_TRUE(same(readImage(path("a.jpg")), img));
  EXPECT_TRUE(same(readImage(path("b.png")), cv::imread(path("b.png"), cv::IMREAD_UNCHANGED)));
  writePng(path("noext"), img, 1);
  EXPECT_TRUE(same(readImage(path("noext")), img));
}

// ---- bad files ----------------------------------------------------------------------------------

TEST_F(ImageFile, MissingEmptyAndUnknownFilesNameThePathAndTheFormats) {
  const std::string missing = path("missing.png");
  EXPECT_NE(errorOf([&] { readImage(missing); }).find(missing + ": cannot open image file (No such file"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { readImage(dir_.string()); }).find(dir_.string() + ": not a regular file"), std::string::npos);
  writeBytes(path("empty.png"), "");
  EXPECT_EQ(errorOf([&] { readImage(path("empty.png")); }), path("empty.png") + ": image file is empty");
  for (const std::string& content : {std::string("GIF89a\x01\x00\x01\x00", 10), std::string("BM\x36\x00\x00\x00"),
                                     std::string("not an image\n"), std::string("\x89PNG", 4),
                                     std::string("\xFF\xD8", 2)}) {
    writeBytes(path("x.png"), content);
    const std::string e = errorOf([&] { readImage(path("x.png")); });
    EXPECT_EQ(e.rfind(path("x.png") + ": not a PNG or JPEG file", 0), 0u) << e;
    EXPECT_NE(e.find("supported image formats: PNG"), std::string::npos) << e;
  }
  EXPECT_THROW(readImage(missing), DataError);  // ImageError is a DataError
}

TEST_F(ImageFile, EveryTruncationOfAPngOrJpegIsAnErrorNamingTheFile) {
  const cv::Mat img = photo(9, 14, 3);
  ASSERT_TRUE(cv::imwrite(path("full.png"), img));
  ASSERT_TRUE(cv::imwrite(path("full.jpg"), img));
  for (const char* name : {"full.png", "full.jpg"}) {
    const std::string full = bytesOf(path(name));
    ASSERT_NO_THROW(readImage(path(name)));
    const std::string cut = path(std::string("cut_") + name);
    for (size_t n = 0; n < full.size(); ++n) {
      writeBytes(cut, full.substr(0, n));
      const std::string e = errorOf([&] { readImage(cut); });
      ASSERT_EQ(e.rfind(cut + ": ", 0), 0u) << name << " cut at " << n << ": " << e;
    }
  }
  // The messages say what happened.
  const std::string png = bytesOf(path("full.png"));
  writeBytes(path("t.png"), png.substr(0, png.size() / 2));
  EXPECT_EQ(errorOf([&] { readImage(path("t.png")); }),
            path("t.png") + ": cannot decode PNG: the file is truncated (it ends at byte " +
                std::to_string(png.size() / 2) + ")");
  const std::string jpg = bytesOf(path("full.jpg"));
  writeBytes(path("t.jpg"), jpg.substr(0, jpg.size() - 40));
  EXPECT_EQ(errorOf([&] { readImage(path("t.jpg")); }),
            path("t.jpg") + ": cannot decode JPEG: Premature end of JPEG file");
  // Stricter than OpenCV, which returns this one with its lower part grey (and a warning on stderr).
  EXPECT_FALSE(cv::imread(path("t.jpg"), cv::IMREAD_UNCHANGED).empty());
}

TEST_F(ImageFile, CorruptFilesAreErrorsNeverCrashes) {
  const cv::Mat img = photo(16, 20, 3);
  ASSERT_TRUE(cv::imwrite(path("ok.png"), img));
  ASSERT_TRUE(cv::imwrite(path("ok.jpg"), img));
  // The signature, then garbage.
  writeBytes(path("g.png"), bytesOf(path("ok.png")).substr(0, 8) + std::string(64, 'x'));
  EXPECT_EQ(errorOf([&] { readImage(path("g.png")); }).rfind(path("g.png") + ": cannot decode PNG: ", 0), 0u);
  writeBytes(path("g.jpg"), std::string("\xFF\xD8\xFF", 3) + std::string(64, 'x'));
  EXPECT_EQ(errorOf([&] { readImage(path("g.jpg")); }).rfind(path("g.jpg") + ": cannot decode JPEG: ", 0), 0u);
  // A flipped byte in the last IDAT's CRC (the file ends with it, then the 12 bytes of IEND); one in its
  // compressed data, whose end is zlib's own check.
  std::string png = bytesOf(path("ok.png"));
  png[png.size() - 14] ^= 0x55;
  writeBytes(path("crc.png"), png);
  EXPECT_EQ(errorOf([&] { readImage(path("crc.png")); }), path("crc.png") + ": cannot decode PNG: IDAT: CRC error");
  png = bytesOf(path("ok.png"));
  png[png.size() - 20] ^= 0x55;
  writeBytes(path("adler.png"), png);
  EXPECT_EQ(errorOf([&] { readImage(path("adler.png")); }),
            path("adler.png") + ": cannot decode PNG: IDAT: incorrect data check");
  // Random damage: decoded (a JPEG may survive some) or an ImageError, nothing else.
  std::mt19937 rng(42);
  for (const char* name : {"ok.png", "ok.jpg"}) {
    const std::string good = bytesOf(path(name));
    for (int k = 0; k < 300; ++k) {
      std::string b = good;
      for (int j = 0; j < 1 + k % 4; ++j) b[3 + rng() % (b.size() - 3)] = static_cast<char>(rng());
      writeBytes(path("bad"), b);
      try {
        const cv::Mat m = readImage(path("bad"));
        EXPECT_FALSE(m.empty());
      } catch (const ImageError& e) {
        EXPECT_EQ(std::string(e.what()).rfind(path("bad") + ": ", 0), 0u) << e.what();
      }
    }
  }
}

TEST_F(ImageFile, HugeHeaderIsRefusedBeforeAllocating) {
  RawPng p;  // a valid 1x1 grey PNG whose IHDR is then made to claim 1000000 x 2000 pixels (CRC fixed)
  p.width = 1;
  p.height = 1;
  p.rows = {{0}};
  writeRawPng(path("one.png"), p);
  std::string b = bytesOf(path("one.png"));
  auto put32 = [&](size_t at, uint32_t v) {
    for (int i = 0; i < 4; ++i) b[at + i] = static_cast<char>((v >> (24 - 8 * i)) & 0xFF);
  };
  put32(16, 1000000);  // IHDR width (libpng's own limit is 1000000 per side)
  put32(20, 2000);     // height: 2e9 pixels, over OpenCV's and readImage's 2^30
  put32(29, static_cast<uint32_t>(crc32(0, reinterpret_cast<const Bytef*>(b.data() + 12), 17)));
  writeBytes(path("huge.png"), b);
  EXPECT_EQ(errorOf([&] { readImage(path("huge.png")); }),
            path("huge.png") + ": cannot decode PNG: image size 1000000x2000 is outside 1..2^20 per side and 2^30 "
                               "pixels in all");
  bool opencv_refuses = true;  // OpenCV 4.6 throws from its size check; other versions return an empty Mat
  try {
    opencv_refuses = cv::imread(path("huge.png"), cv::IMREAD_UNCHANGED).empty();
  } catch (const cv::Exception&) {
  }
  EXPECT_TRUE(opencv_refuses);
}

TEST_F(ImageFile, WritePngRefusesOtherTypesAndLevelsAndNamesTheFile) {
  const std::string p = path("w.png");
  auto msg = [&](const cv::Mat& m, int level) {
    try {
      writePng(p, m, level);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string unsupported = p + ": cannot write PNG: unsupported image type";
  EXPECT_EQ(msg(cv::Mat(4, 4, CV_32FC1, cv::Scalar(0)), 1).rfind(unsupported, 0), 0u);
  EXPECT_EQ(msg(cv::Mat(4, 4, CV_16UC3, cv::Scalar(0)), 1).rfind(unsupported, 0), 0u);
  EXPECT_EQ(msg(cv::Mat(), 1).rfind(p + ": cannot write PNG", 0), 0u);
  EXPECT_EQ(msg(cv::Mat(4, 4, CV_8UC1, cv::Scalar(0)), 10),
            p + ": cannot write PNG: compression level 10 outside 0..9");
  const std::string nodir = path("no/such/dir.png");
  try {
    writePng(nodir, cv::Mat(4, 4, CV_8UC1, cv::Scalar(0)), 1);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind(nodir + ": cannot write PNG", 0), 0u) << e.what();
  }
  EXPECT_FALSE(fs::exists(p));
  // Nothing but the final file is left (written whole, then renamed).
  writePng(p, cv::Mat(4, 4, CV_8UC1, cv::Scalar(3)), 1);
  size_t files = 0;
  for (const auto& e : fs::directory_iterator(dir_)) files += e.is_regular_file() ? 1 : 0;
  EXPECT_EQ(files, 1u);
}

}  // namespace
}  // namespace rsvio::io
