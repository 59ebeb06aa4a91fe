// The bad-input corpus of source.euroc: one test per case, each checking the message (file, line, field)
// and whether the case is fatal (DataError from open/readFrame) or a warning with the sample dropped.
// The table of decisions is docs/datasets.md. Fixtures are written by the tests into temp folders.
#include "source_fixture.h"

using namespace rsvio;
using namespace rsvio::test;

namespace {

// Opens `dir` with `params`, expects a fatal DataError and returns its message (one line).
std::string fatal(const fs::path& dir, const nlohmann::json& params = nlohmann::json::object()) {
  auto src = makeSource(params);
  const std::string msg = openError(*src, dir);
  EXPECT_FALSE(msg.empty()) << "open() succeeded; warnings:\n" << joined(src->warnings());
  EXPECT_EQ(msg.find('\n'), std::string::npos) << "not one line: " << msg;
  if (std::getenv("RSVIO_PRINT_MESSAGES")) std::printf("MSG %s\n", msg.c_str());  // for reviewing the wording
  return msg;
}

// Opens `dir`, expects success, returns the source for checks on warnings and samples.
std::unique_ptr<DataSource> opened(const fs::path& dir, const nlohmann::json& params = nlohmann::json::object()) {
  auto src = makeSource(params);
  const std::string msg = openError(*src, dir);
  EXPECT_EQ(msg, "");
  return src;
}

#define EXPECT_HAS(msg, needle) EXPECT_NE((msg).find(needle), std::string::npos) << (msg)

// A dataset with the given IMU data lines after EuRoC's header.
void writeImuLines(const fs::path& dir, const std::string& lines) {
  writeText(imuCsv(dir), "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
                         "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n" + lines);
}

// IMU line for sample k of the default spec (200 Hz from 0.1 s before the first frame).
std::string imuLine(int k, const std::string& accel_y = "0.2") {
  const int64_t t = DatasetSpec().t0_ns - DatasetSpec().imu_margin_ns + k * DatasetSpec().imu_dt_ns;
  return std::to_string(t) + ",0.01,-0.02,0.0,0.1," + accel_y + ",9.81\n";
}

std::string imuLines(int from, int to) {
  std::string s;
  for (int k = from; k < to; ++k) s += imuLine(k);
  return s;
}

constexpr int kImuCount = 81;  // 0.1 s + 4 frames * 50 ms + 0.1 s at 200 Hz, inclusive

std::string stampName(int i) { return std::to_string(frameStamp(DatasetSpec(), i)); }

}  // namespace

// ---- CSV structure -------------------------------------------------------------------------------

TEST(BadInput, TruncatedImuRowInTheMiddleIsFatal) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  writeImuLines(tmp.path(), imuLines(0, 3) + "999,0.1,0.2\n" + imuLines(4, kImuCount));
  const std::string msg = fatal(tmp.path());
  EXPECT_HAS(msg, imuCsv(tmp.path()).string() + ":5: expected 7 fields");
  EXPECT_HAS(msg, "found 3");
}

TEST(BadInput, TruncatedLastImuRowIsDroppedWithAWarning) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  std::string last = imuLine(kImuCount - 1);
  writeImuLines(tmp.path(), imuLines(0, kImuCount - 1) + last.substr(0, last.size() / 2));  // no newline
  auto src = opened(tmp.path());
  EXPECT_EQ(src->imu().size(), static_cast<size_t>(kImuCount - 1));
  EXPECT_TRUE(anyContains(src->warnings(), ":" + std::to_string(kImuCount + 1) + ": last line is truncated"))
      << joined(src->warnings());
}

TEST(BadInput, WrongColumnCountInImageIndexIsFatal) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  replaceInFile(camCsv(tmp.path()), stampName(1) + ".png\n", stampName(1) + ".png,extra\n");
  const std::string msg = fatal(tmp.path());
  EXPECT_HAS(msg, camCsv(tmp.path()).string() + ":3: expected 2 fields (timestamp [ns], filename), found 3");
}

TEST(BadInput, TooManyImuColumnsIsFatal) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  writeImuLines(tmp.path(), imuLines(0, 2) + "1,2,3,4,5,6,7,8\n" + imuLines(3, kImuCount));
  EXPECT_HAS(fatal(tmp.path()), ":4: expected 7 fields");
}

TEST(BadInput, NonNumericImuFieldIsFatalWithLineColumnAndField) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  writeImuLines(tmp.path(), imuLines(0, 2) + imuLine(2, "abc") + imuLines(3, kImuCount));
  const std::string msg = fatal(tmp.path());
  const size_t col = imuLine(2).find(",0.2,") + 2;  // 1-based column of a_RS_S_y
  EXPECT_HAS(msg, imuCsv(tmp.path()).string() + ":4:" + std::to_string(col) + ": field 'a_RS_S_y [m s^-2]'");
  EXPECT_HAS(msg, "expected a number, found 'abc'");
}

TEST(BadInput, NonIntegerImageTimestampIsFatal) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  replaceInFile(camCsv(tmp.path()), stampName(2) + ",", "1.5e12,");
  const std::string msg = fatal(tmp.path());
  EXPECT_HAS(msg, camCsv(tmp.path()).string() + ":4:1: field 'timestamp [ns]': expected an integer, found '1.5e12'");
}

TEST(BadInput, BinaryJunkInCsvIsReportedPrintably) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  writeImuLines(tmp.path(), imuLines(0, 2) + std::string("\x01\x02\xff,1,2,3,4,5,6\n") + imuLines(3, kImuCount));
  const std::string msg = fatal(tmp.path());
  EXPECT_HAS(msg, ":4:1: field 'timestamp [ns]': expected an integer, found '???'");
}

TEST(BadInput, WindowsLineEndingsAndByteOrderMarkAreAccepted) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  std::string csv = "\xEF\xBB\xBF#timestamp [ns],filename\r\n";
  for (int i = 0; i < 5; ++i) csv += stampName(i) + "," + stampName(i) + ".png\r\n";
  writeText(camCsv(tmp.path()), csv);
  auto src = opened(tmp.path());
  EXPECT_EQ(src->numFrames(), 5u);
}

TEST(BadInput, HeaderWithoutHashIsSkippedWithAWarning) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  replaceInFile(camCsv(tmp.path()), "#timestamp [ns],filename", "timestamp,filename");
  auto src = opened(tmp.path());
  EXPECT_EQ(src->numFrames(), 5u);
  EXPECT_TRUE(anyContains(src->warnings(), camCsv(tmp.path()).string() + ":1: no field is a number; taken as a column header"))
      << joined(src->warnings());
}

TEST(BadInput, CorruptFirstImuRowIsNotMistakenForAHeader) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  writeText(imuCsv(tmp.path()), "x" + imuLine(0) + imuLines(1, kImuCount));
  EXPECT_HAS(fatal(tmp.path()), imuCsv(tmp.path()).string() + ":1:1: field 'timestamp [ns]': expected an integer");
}

TEST(BadInput, EmptyImageIndexIsFatal) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  writeText(camCsv(tmp.path()), "#timestamp [ns],filename\n");
  EXPECT_HAS(fatal(tmp.path()), camCsv(tmp.path()).string() + ": no frames listed");
}

// ---- IMU values and timestamps -----------------------------------------------------------------

TEST(BadInput, NanImuValueDropsTheSampleWithAWarning) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  writeImuLines(tmp.path(), imuLines(0, 10) + imuLine(10, "nan") + imuLines(11, kImuCount));
  auto src = opened(tmp.path());
  EXPECT_EQ(src->imu().size(), static_cast<size_t>(kImuCount - 1));
  EXPECT_TRUE(anyContains(src->warnings(), ":12:"));
  EXPECT_TRUE(anyContains(src->warnings(), "field 'a_RS_S_y [m s^-2]' is nan; IMU sample dropped"))
      << joined(src->warnings());
}

TEST(BadInput, InfImuValueDropsTheSampleWithAWarning) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  writeImuLines(tmp.path(), imuLines(0, 10) + imuLine(10, "-inf") + imuLines(11, kImuCount));
  auto src = opened(tmp.path());
  EXPECT_EQ(src->imu().size(), static_cast<size_t>(kImuCount - 1));
  EXPECT_TRUE(anyContains(src->warnings(), "is -inf; IMU sample dropped")) << joined(src->warnings());
}

TEST(BadInput, ManyNanImuValuesAreSummarised) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  std::string lines;
  for (int k = 0; k < kImuCount; ++k) lines += imuLine(k, k % 10 == 5 ? "nan" : "0.2");
  writeImuLines(tmp.path(), lines);
  auto src = opened(tmp.path());
  EXPECT_TRUE(anyContains(src->warnings(), "... and 3 more IMU samples with NaN/inf values dropped"))
      << joined(src->warnings());
}

TEST(BadInput, DecreasingImuTimestampIsFatal) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  writeImuLines(tmp.path(), imuLines(0, 5) + imuLine(3) + imuLines(6, kImuCount));
  const std::string msg = fatal(tmp.path());
  EXPECT_HAS(msg, imuCsv(tmp.path()).string() + ":7:1: field 'timestamp [ns]'");
  EXPECT_HAS(msg, "on line 6 (IMU timestamps must increase)");
}

TEST(BadInput, DuplicateImuTimestampDropsTheLaterSampleWithAWarning) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  writeImuLines(tmp.path(), imuLines(0, 5) + imuLine(4, "0.3") + imuLines(5, kImuCount));
  auto src = opened(tmp.path());
  EXPECT_EQ(src->imu().size(), static_cast<size_t>(kImuCount));
  EXPECT_DOUBLE_EQ(src->imu()[4].accel_m_s2.y(), 0.2);  // the first one is kept
  EXPECT_TRUE(anyContains(src->warnings(), ":7:1: duplicate IMU timestamp")) << joined(src->warnings());
  EXPECT_TRUE(anyContains(src->warnings(), "(also on line 6); sample dropped")) << joined(src->warnings());
}

// Runs stream the IMU (DataSource::imuReader) instead of holding it: the reader must keep exactly
// the samples open() kept (a dropped duplicate, NaN and a truncated last line here) and add no warning.
TEST(BadInput, StreamedImuKeepsTheSamplesOpenKept) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  std::string lines = imuLines(0, 5) + imuLine(4, "0.3") + imuLines(5, 10) + imuLine(10, "nan") +
                      imuLines(11, kImuCount) + "123";
  writeImuLines(tmp.path(), lines);
  auto src = opened(tmp.path());
  const size_t warnings = src->warnings().size();
  EXPECT_GE(warnings, 3u) << joined(src->warnings());
  auto reader = src->imuReader();
  std::vector<ImuSample> streamed;
  for (ImuSample s; reader->next(s);) streamed.push_back(s);
  EXPECT_EQ(src->warnings().size(), warnings);
  const std::vector<ImuSample>& all = src->imu();
  ASSERT_EQ(streamed.size(), static_cast<size_t>(kImuCount - 1));
  ASSERT_EQ(streamed.size(), all.size());
  for (size_t k = 0; k < all.size(); ++k) {
    EXPECT_EQ(streamed[k].t_ns, all[k].t_ns);
    EXPECT_EQ(streamed[k].gyro_rad_s, all[k].gyro_rad_s);
    EXPECT_EQ(streamed[k].accel_m_s2, all[k].accel_m_s2);
  }
  EXPECT_DOUBLE_EQ(streamed[4].accel_m_s2.y(), 0.2);  // the first of the duplicates
  // A second reader starts from the first sample again.
  ImuSample first;
  ASSERT_TRUE(src->imuReader()->next(first));
  EXPECT_EQ(first.t_ns, all.front().t_ns);
}

TEST(BadInput, DecreasingImageTimestampIsFatal) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  replaceInFile(camCsv(tmp.path()), stampName(3) + "," + stampName(3), stampName(1) + "," + stampName(3));
  const std::string msg = fatal(tmp.path());
  EXPECT_HAS(msg, camCsv(tmp.path()).string() + ":5:1: field 'timestamp [ns]'");
  EXPECT_HAS(msg, "is earlier than " + stampName(2) + " ns on line 4 (image timestamps must increase)");
}

TEST(BadInput, DuplicateImageTimestampDropsTheLaterFrameWithAWarning) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  replaceInFile(camCsv(tmp.path()), stampName(3) + "," + stampName(3), stampName(2) + "," + stampName(3));
  auto src = opened(tmp.path());
  EXPECT_EQ(src->numFrames(), 4u);
  EXPECT_EQ(src->frameTime(3), frameStamp(DatasetSpec(), 4));
  EXPECT_TRUE(anyContains(src->warnings(), ":5:1: duplicate image timestamp " + stampName(2)))
      << joined(src->warnings());
}

TEST(BadInput, ImuGapInsideTheCameraSpanIsFatal) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  writeImuLines(tmp.path(), imuLines(0, 30) + imuLines(50, kImuCount));  // 105 ms gap mid-sequence
  const std::string msg = fatal(tmp.path());
  EXPECT_HAS(msg, imuCsv(tmp.path()).string() + ":32: gap of 105.0 ms in the IMU data");
  EXPECT_HAS(msg, "(line 31)");
  EXPECT_HAS(msg, "exceeds max_imu_gap_ms = 50.0 inside the camera's time span");
}

TEST(BadInput, ImuGapAcceptedWithALargerMaximum) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  writeImuLines(tmp.path(), imuLines(0, 30) + imuLines(50, kImuCount));
  auto src = opened(tmp.path(), {{"max_imu_gap_ms", 200.0}});
  EXPECT_EQ(src->imu().size(), static_cast<size_t>(kImuCount - 20));
}

TEST(BadInput, ImuGapOutsideTheCameraSpanIsAWarning) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  writeImuLines(tmp.path(), imuLine(0) + imuLines(15, kImuCount));  // gap ends before the first frame
  auto src = opened(tmp.path());
  EXPECT_TRUE(anyContains(src->warnings(), "gap of 75.0 ms")) << joined(src->warnings());
  EXPECT_TRUE(anyContains(src->warnings(), "outside the camera's time span")) << joined(src->warnings());
}

TEST(BadInput, MissingImuFolderIsAWarningAndNoImu) {
  TempDir tmp;
  DatasetSpec spec;
  spec.imu = false;
  writeDataset(tmp.path(), spec);
  auto src = opened(tmp.path());
  EXPECT_FALSE(src->sensors().has_imu);
  EXPECT_TRUE(anyContains(src->warnings(), "imu0/data.csv not found: no IMU data")) << joined(src->warnings());
}

// ---- images --------------------------------------------------------------------------------------

TEST(BadInput, MissingImageIsFatalAtOpen) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  const fs::path img = tmp.path() / "mav0" / "cam0" / "data" / (stampName(2) + ".png");
  fs::remove(img);
  const std::string msg = fatal(tmp.path());
  EXPECT_HAS(msg, camCsv(tmp.path()).string() + ":4: frame 2 at " + stampName(2) + " ns: image not found: " +
                      img.string());
}

TEST(BadInput, NotAPngIsFatal) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  const fs::path img = tmp.path() / "mav0" / "cam0" / "data" / (stampName(0) + ".png");
  writeText(img, "this is not an image\n");
  const std::string msg = fatal(tmp.path());
  EXPECT_HAS(msg, img.string() + ": frame 0 (timestamp " + stampName(0) + " ns, ");
  EXPECT_HAS(msg, "not a PNG file");
}

TEST(BadInput, EmptyPngFileIsFatal) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  writeText(tmp.path() / "mav0" / "cam0" / "data" / (stampName(0) + ".png"), "");
  EXPECT_HAS(fatal(tmp.path()), "not a PNG file");
}

TEST(BadInput, CorruptPngIsFatalInReadFrame) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  const fs::path img = tmp.path() / "mav0" / "cam0" / "data" / (stampName(3) + ".png");
  std::string bytes = readText(img);
  writeText(img, bytes.substr(0, 8) + std::string(64, 'x'));  // PNG signature, garbage after it
  auto src = opened(tmp.path());
  const std::string msg = errorOf([&] { src->readFrame(3); });
  EXPECT_HAS(msg, img.string() + ": frame 3 (timestamp " + stampName(3) + " ns, " + camCsv(tmp.path()).string() + ":5)");
  EXPECT_HAS(msg, "cannot read or decode image");
}

TEST(BadInput, UnreadableImageIsFatalInReadFrame) {
  if (::geteuid() == 0) GTEST_SKIP() << "root reads files regardless of permissions";
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  const fs::path img = tmp.path() / "mav0" / "cam0" / "data" / (stampName(1) + ".png");
  fs::permissions(img, fs::perms::none);
  auto src = opened(tmp.path());
  EXPECT_HAS(errorOf([&] { src->readFrame(1); }), ": frame 1 (timestamp");
}

TEST(BadInput, WrongImageSizeNamesFrameTimestampPathAndSizes) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  const fs::path yaml = tmp.path() / "mav0" / "cam0" / "sensor.yaml";
  writeText(yaml, eurocCameraYaml(80, 48));
  const std::string msg = fatal(tmp.path());
  const fs::path img = tmp.path() / "mav0" / "cam0" / "data" / (stampName(0) + ".png");
  EXPECT_HAS(msg, img.string() + ": frame 0 (timestamp " + stampName(0) + " ns");
  EXPECT_HAS(msg, "image is 64x48, expected 80x48 from the calibration " + yaml.string());
}

TEST(BadInput, WrongImageSizeLaterInTheSequenceIsFatalInReadFrame) {
  TempDir tmp;
  DatasetSpec spec;
  writeDataset(tmp.path(), spec);
  DatasetSpec small = spec;
  small.width = 32;
  cv::imwrite((tmp.path() / "mav0" / "cam0" / "data" / (stampName(4) + ".png")).string(), testImage(small, 4));
  auto src = opened(tmp.path());
  EXPECT_HAS(errorOf([&] { src->readFrame(4); }), "image is 32x48, expected 64x48");
}

// ---- folders -------------------------------------------------------------------------------------

TEST(BadInput, EmptyFolderIsFatal) {
  TempDir tmp;
  const std::string msg = fatal(tmp.path());
  EXPECT_HAS(msg, tmp.str() + ": folder is empty (expected the EuRoC/ASL layout: mav0/cam0/data.csv");
}

TEST(BadInput, MissingMav0IsFatal) {
  TempDir tmp;
  writeText(tmp.path() / "README.txt", "not a dataset\n");
  EXPECT_HAS(fatal(tmp.path()), tmp.str() + ": no mav0/ folder");
}

TEST(BadInput, MissingDatasetFolderIsFatal) {
  TempDir tmp;
  EXPECT_HAS(fatal(tmp.path() / "nope"), "nope: dataset folder not found");
}

TEST(BadInput, UnknownCameraListsTheCamerasFound) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  EXPECT_HAS(fatal(tmp.path(), {{"camera", "cam2"}}), "no camera folder 'cam2' (found: cam0;");
}

TEST(BadInput, NoCalibrationIsFatal) {
  TempDir tmp;
  DatasetSpec spec;
  spec.sensor_yaml = false;
  writeDataset(tmp.path(), spec);
  EXPECT_HAS(fatal(tmp.path()), "sensor.yaml: no calibration found");
}
