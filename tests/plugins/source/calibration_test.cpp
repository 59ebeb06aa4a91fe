// Bad calibration input through source.euroc (YAML syntax, wrong types and counts, unsupported models,
// bad transforms, DSO photometric files), and the framework's CSV and photometric readers directly.
#include <cmath>

#include "rsvio/io/calibration.h"
#include "rsvio/io/csv.h"
#include "source_fixture.h"

using namespace rsvio;
using namespace rsvio::test;

namespace {

#define EXPECT_HAS(msg, needle) EXPECT_NE((msg).find(needle), std::string::npos) << (msg)

std::string fatal(const fs::path& dir, const nlohmann::json& params = nlohmann::json::object()) {
  auto src = makeSource(params);
  const std::string msg = openError(*src, dir);
  EXPECT_FALSE(msg.empty()) << "open() succeeded; warnings:\n" << joined(src->warnings());
  EXPECT_EQ(msg.find('\n'), std::string::npos) << "not one line: " << msg;
  if (std::getenv("RSVIO_PRINT_MESSAGES")) std::printf("MSG %s\n", msg.c_str());  // for reviewing the wording
  return msg;
}

// A EuRoC dataset whose cam0/sensor.yaml has `from` replaced by `to`; returns the yaml path.
fs::path datasetWithYamlEdit(const TempDir& tmp, const std::string& from, const std::string& to) {
  writeDataset(tmp.path(), DatasetSpec());
  const fs::path yaml = tmp.path() / "mav0" / "cam0" / "sensor.yaml";
  replaceInFile(yaml, from, to);
  return yaml;
}

}  // namespace

// ---- YAML ----------------------------------------------------------------------------------------

TEST(BadCalibration, YamlSyntaxErrorKeepsYamlCppsLineAndColumn) {
  TempDir tmp;
  const fs::path yaml = datasetWithYamlEdit(tmp, "rate_hz: 20\n", "rate_hz: [20\n");
  const std::string msg = fatal(tmp.path());
  EXPECT_HAS(msg, yaml.string() + ":");
  EXPECT_HAS(msg, ": invalid YAML: ");
}

TEST(BadCalibration, WrongTypeNamesTheKey) {
  TempDir tmp;
  const fs::path yaml =
      datasetWithYamlEdit(tmp, "intrinsics: [45.8654, 45.7296, 31.7215, 23.8375]", "intrinsics: abc");
  const std::string msg = fatal(tmp.path());
  EXPECT_HAS(msg, yaml.string() + ":18:13: key 'intrinsics': expected a list of numbers [fu, fv, cu, cv], found 'abc'");
}

TEST(BadCalibration, WrongCountNamesTheKey) {
  TempDir tmp;
  datasetWithYamlEdit(tmp, "intrinsics: [45.8654, 45.7296, 31.7215, 23.8375]", "intrinsics: [45.8654, 45.7296, 31.7]");
  EXPECT_HAS(fatal(tmp.path()), "key 'intrinsics': expected 4 numbers [fu, fv, cu, cv], found 3");
}

TEST(BadCalibration, NonFiniteValueNamesTheElement) {
  TempDir tmp;
  datasetWithYamlEdit(tmp, "intrinsics: [45.8654, 45.7296, 31.7215", "intrinsics: [45.8654, 45.7296, nan");
  EXPECT_HAS(fatal(tmp.path()), "key 'intrinsics[2]': expected a finite number, found 'nan'");
}

TEST(BadCalibration, MissingKeyIsNamed) {
  TempDir tmp;
  const fs::path yaml = datasetWithYamlEdit(tmp, "resolution: [64, 48]\n", "");
  EXPECT_HAS(fatal(tmp.path()), yaml.string() + ":2:1: missing key 'resolution'");
}

TEST(BadCalibration, UnsupportedDistortionModelListsTheSupportedOnes) {
  TempDir tmp;
  datasetWithYamlEdit(tmp, "distortion_model: radial-tangential", "distortion_model: fov");
  EXPECT_HAS(fatal(tmp.path()), "key 'distortion_model': unsupported distortion model 'fov' (supported: "
                                "radial-tangential/radtan, equidistant/equi, none)");
}

TEST(BadCalibration, WrongDistortionCoefficientCount) {
  TempDir tmp;
  datasetWithYamlEdit(tmp, "0.00019359, 1.76187114e-05]", "0.00019359]");
  EXPECT_HAS(fatal(tmp.path()), "key 'distortion_coefficients': expected 4 numbers [k1, k2, p1, p2], found 3");
}

TEST(BadCalibration, DistortionNoneAcceptsZeroPaddingOnly) {
  TempDir tmp;
  datasetWithYamlEdit(tmp, "distortion_model: radial-tangential\ndistortion_coefficients: [-0.28340811",
                      "distortion_model: none\ndistortion_coefficients: [0.0");
  EXPECT_HAS(fatal(tmp.path()), "key 'distortion_coefficients': non-zero coefficients with distortion model 'none'");
  TempDir tmp2;
  datasetWithYamlEdit(tmp2, "distortion_coefficients: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]",
                      "distortion_coefficients: [0, 0, 0, 0]");
  replaceInFile(tmp2.path() / "mav0" / "cam0" / "sensor.yaml", "radial-tangential", "none");
  auto src = makeSource();
  ASSERT_EQ(openError(*src, tmp2.path()), "");
  EXPECT_EQ(src->sensors().camera.distortion, "none");
  EXPECT_EQ(src->sensors().camera.distortion_coeffs.size(), 0);
}

TEST(BadCalibration, ExtrinsicThatIsNotARotation) {
  TempDir tmp;
  datasetWithYamlEdit(tmp, "data: [0.0148655429818,", "data: [0.5148655429818,");
  EXPECT_HAS(fatal(tmp.path()), "key 'T_BS': rotation part is not a rotation");
}

TEST(BadCalibration, EmptyYamlFile) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  writeText(tmp.path() / "mav0" / "cam0" / "sensor.yaml", "");
  EXPECT_HAS(fatal(tmp.path()), "sensor.yaml: expected a camera sensor.yaml to be a map of keys, found nothing");
}

TEST(BadCalibration, KalibrCamchainWithoutTheCamera) {
  TempDir tmp;
  DatasetSpec spec;
  spec.camera = "cam1";
  spec.sensor_yaml = false;
  writeDataset(tmp.path(), spec);
  writeText(tmp.path() / "camchain.yaml",
            "cam0:\n  camera_model: pinhole\n  intrinsics: [1, 1, 1, 1]\n  resolution: [64, 48]\n");
  EXPECT_HAS(fatal(tmp.path(), {{"camera", "cam1"}}), "camchain.yaml: no camera 'cam1' in the camchain (found: cam0)");
}

TEST(BadCalibration, KalibrUnsupportedCameraModel) {
  TempDir tmp;
  DatasetSpec spec;
  spec.sensor_yaml = false;
  writeDataset(tmp.path(), spec);
  writeText(tmp.path() / "camchain.yaml",
            "cam0:\n  camera_model: omni\n  intrinsics: [0.8, 1, 1, 1, 1]\n  resolution: [64, 48]\n");
  EXPECT_HAS(fatal(tmp.path()), "camchain.yaml:2:17: key 'camera_model': unsupported camera model 'omni' (supported: pinhole)");
}

TEST(BadCalibration, NegativeImuNoise) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  replaceInFile(tmp.path() / "mav0" / "imu0" / "sensor.yaml", "gyroscope_noise_density: 1.6968e-04",
                "gyroscope_noise_density: -1.6968e-04");
  EXPECT_HAS(fatal(tmp.path()), "imu0/sensor.yaml:11:26: key 'gyroscope_noise_density': must be > 0");
}

TEST(BadCalibration, MissingImuNoiseKeyIsAWarning) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  replaceInFile(tmp.path() / "mav0" / "imu0" / "sensor.yaml", "gyroscope_random_walk: 1.9393e-05\n", "");
  auto src = makeSource();
  ASSERT_EQ(openError(*src, tmp.path()), "");
  EXPECT_TRUE(anyContains(src->warnings(), "missing gyroscope_random_walk; using rsvio's defaults"))
      << joined(src->warnings());
}

TEST(BadCalibration, CalibrationFileParamThatDoesNotExist) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  EXPECT_HAS(fatal(tmp.path(), {{"calibration_file", "calib/nope.yaml"}}),
             "calib/nope.yaml: calibration file not found (params.calibration_file)");
}

// ---- DSO photometric files through the source ---------------------------------------------------

TEST(BadCalibration, NonIncreasingInverseResponse) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  std::string pcalib;
  for (int k = 0; k < 256; ++k) pcalib += std::to_string(k == 12 ? 5 : k) + " ";
  writeText(tmp.path() / "dso" / "cam0" / "pcalib.txt", pcalib + "\n");
  const std::string msg = fatal(tmp.path());
  EXPECT_HAS(msg, "pcalib.txt:1:");
  EXPECT_HAS(msg, "G^-1 must strictly increase, but value 12 (5) is not greater than value 11 (11)");
}

TEST(BadCalibration, VignetteOfTheWrongSize) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  fs::create_directories(tmp.path() / "dso" / "cam0");
  cv::imwrite((tmp.path() / "dso" / "cam0" / "vignette.png").string(), cv::Mat(48, 32, CV_8UC1, cv::Scalar(7)));
  EXPECT_HAS(fatal(tmp.path()), "vignette.png: vignette is 32x48, expected the raw image size 64x48");
}

TEST(BadCalibration, NonPositiveExposureTime) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  writeText(tmp.path() / "dso" / "cam0" / "times.txt", "# id t exposure\n1000000000000 1000.0 2.0\n1050000000000 1000.05 -1\n");
  EXPECT_HAS(fatal(tmp.path()), "times.txt:3:23: field 'exposure [ms]': exposure must be a finite number > 0 ms, found '-1'");
}

// ---- framework readers directly -------------------------------------------------------------------

TEST(CsvReader, ReportsLineColumnAndFieldName) {
  TempDir tmp;
  writeText(tmp.path() / "a.csv", "# header\n\n1, 2.5 ,x\n4,five,6\n");
  io::CsvReader csv((tmp.path() / "a.csv").string(), {"a", "b", "c"});
  ASSERT_TRUE(csv.next());
  EXPECT_EQ(csv.line(), 3);
  EXPECT_EQ(csv.getInt64(0), 1);
  EXPECT_DOUBLE_EQ(csv.getDouble(1), 2.5);
  EXPECT_EQ(csv.column(1), 4);  // after the blank that follows the comma
  EXPECT_EQ(csv.getString(2), "x");
  ASSERT_TRUE(csv.next());
  const std::string msg = errorOf([&] { csv.getDouble(1); });
  EXPECT_EQ(msg, (tmp.path() / "a.csv").string() + ":4:3: field 'b': expected a number, found 'five'");
  EXPECT_FALSE(csv.next());
}

TEST(CsvReader, WhitespaceDelimitedWithTextHeader) {
  TempDir tmp;
  writeText(tmp.path() / "t.txt", "id time\n a   1.0\t2\nb 3");
  io::CsvFormat f;
  f.delimiter = io::CsvFormat::Delimiter::kWhitespace;
  f.skip_text_header = true;
  io::CsvReader csv((tmp.path() / "t.txt").string(), {"id", "time"}, f);
  ASSERT_TRUE(csv.next());
  EXPECT_EQ(csv.size(), 3u);
  EXPECT_EQ(csv.column(2), 10);
  EXPECT_FALSE(csv.rowUnterminated());
  ASSERT_TRUE(csv.next());
  EXPECT_TRUE(csv.rowUnterminated());
  EXPECT_NO_THROW(csv.expectFieldCount());
}

TEST(CsvReader, MissingFileIsADataError) {
  EXPECT_EQ(errorOf([] { io::CsvReader csv("/nonexistent/x.csv", {}); }), "/nonexistent/x.csv: cannot open file");
}

TEST(CsvReader, NumberParsing) {
  EXPECT_EQ(io::parseInt64("+42"), 42);
  EXPECT_EQ(io::parseInt64("-7"), -7);
  EXPECT_FALSE(io::parseInt64("1.0"));
  EXPECT_FALSE(io::parseInt64("99999999999999999999"));  // out of range, not clamped
  EXPECT_DOUBLE_EQ(*io::parseDouble("-1.5e-3"), -1.5e-3);
  EXPECT_DOUBLE_EQ(*io::parseDouble(".5"), 0.5);
  EXPECT_TRUE(std::isnan(*io::parseDouble("NaN")));
  EXPECT_EQ(*io::parseDouble("-inf"), -std::numeric_limits<double>::infinity());
  EXPECT_FALSE(io::parseDouble("1e999"));
  EXPECT_FALSE(io::parseDouble("1,5"));
  EXPECT_FALSE(io::parseDouble(""));
  EXPECT_FALSE(io::parseDouble("nanx"));
}

TEST(PhotometricFiles, InverseResponseCountMustBe256Or65536) {
  TempDir tmp;
  writeText(tmp.path() / "pcalib.txt", "1 2 3\n4 5\n");
  EXPECT_EQ(errorOf([&] { io::readInverseResponse((tmp.path() / "pcalib.txt").string()); }),
            (tmp.path() / "pcalib.txt").string() +
                ": expected 256 (8-bit) or 65536 (16-bit) inverse-response values, found 5");
}

TEST(PhotometricFiles, ExposureTimesWithAndWithoutExposureColumn) {
  TempDir tmp;
  writeText(tmp.path() / "times.txt", "00000 1403636579.763555584 1.5\n00001 1403636579.813555456\n");
  const auto e = io::readExposureTimes((tmp.path() / "times.txt").string());
  ASSERT_EQ(e.size(), 2u);
  EXPECT_EQ(e[0].id, "00000");
  EXPECT_EQ(e[0].t_ns, 1403636579763555584);  // exact, no double rounding
  EXPECT_DOUBLE_EQ(e[0].exposure_ms, 1.5);
  EXPECT_TRUE(std::isnan(e[1].exposure_ms));
  EXPECT_EQ(e[1].line, 2);
}

TEST(PhotometricFiles, VignetteThatIsNotAPng) {
  TempDir tmp;
  writeText(tmp.path() / "vignette.png", "GIF89a");
  EXPECT_HAS(errorOf([&] { io::readVignette((tmp.path() / "vignette.png").string()); }), "vignette is not a PNG file");
}
