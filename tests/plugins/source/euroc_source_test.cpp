// source.euroc on well-formed datasets: EuRoC (sensor.yaml), TUM-VI (Kalibr camchain, imu_config.yaml,
// DSO photometric files), the TUM rolling-shutter dataset (cam0 global / cam1 rolling, 16-bit, stamps
// of the first row), timestamp conversion, resizing, calibration choice, streaming. All through the host.
#include <Eigen/Geometry>
#include <cstdio>

#include "source_fixture.h"

using namespace rsvio;
using namespace rsvio::test;

namespace {

// A Kalibr 4x4 written as 4 lists of 4, with enough digits to stay a rotation.
std::string kalibrMatrix(const Eigen::Isometry3d& T, const std::string& indent) {
  std::string s;
  const Eigen::Matrix4d m = T.matrix();
  for (int r = 0; r < 4; ++r) {
    char buf[160];
    std::snprintf(buf, sizeof(buf), "%s- [%.17g, %.17g, %.17g, %.17g]\n", indent.c_str(), m(r, 0), m(r, 1), m(r, 2),
                  m(r, 3));
    s += buf;
  }
  return s;
}

Eigen::Isometry3d someTransform(double angle, const Eigen::Vector3d& axis, const Eigen::Vector3d& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  T.translation() = t;
  return T;
}

std::string kalibrCamera(const std::string& name, int w, int h, const std::string& extra) {
  return name + ":\n" + extra +
         "  camera_model: pinhole\n"
         "  distortion_coeffs: [0.0034823894022493434, 0.0007150348452162257, -0.0020532361418706202,\n"
         "    0.00020293673591811182]\n"
         "  distortion_model: equidistant\n"
         "  intrinsics: [19.097847715128717, 19.09733070521226, 25.493170605935475, 25.68974428996504]\n"
         "  resolution: [" + std::to_string(w) + ", " + std::to_string(h) + "]\n"
         "  rostopic: /" + name + "/image_raw\n";
}

void expectIsometryNear(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double tol) {
  EXPECT_LT((a.matrix() - b.matrix()).cwiseAbs().maxCoeff(), tol) << "\n" << a.matrix() << "\nvs\n" << b.matrix();
}

}  // namespace

TEST(EurocSource, ReadsEurocLayoutWithSensorYaml) {
  TempDir tmp;
  DatasetSpec spec;
  writeDataset(tmp.path(), spec);
  auto src = makeSource();
  src->open(tmp.str());
  EXPECT_TRUE(src->warnings().empty()) << joined(src->warnings());
  ASSERT_EQ(src->numFrames(), 5u);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(src->frameTime(i), frameStamp(spec, i));  // middle row: as stamped

  const CameraCalibration& c = src->sensors().camera;
  EXPECT_EQ(c.width, 64);
  EXPECT_EQ(c.height, 48);
  EXPECT_EQ(c.distortion, "radtan");
  ASSERT_EQ(c.distortion_coeffs.size(), 4);
  EXPECT_DOUBLE_EQ(c.distortion_coeffs[0], -0.28340811);
  EXPECT_DOUBLE_EQ(c.intrinsics[0], 45.8654);
  EXPECT_DOUBLE_EQ(c.intrinsics[3], 23.8375);
  EXPECT_DOUBLE_EQ(c.rate_hz, 20.0);
  EXPECT_EQ(c.line_delay_s, 0.0);
  EXPECT_NEAR(c.T_B_C.translation().x(), -0.0216401454975, 1e-12);
  EXPECT_NEAR(c.T_B_C.linear()(0, 1), -0.999880929698, 1e-6);

  ASSERT_TRUE(src->sensors().has_imu);
  EXPECT_EQ(src->imu().size(), imuSampleCount(spec));
  EXPECT_DOUBLE_EQ(src->sensors().imu.gyro_noise_density, 1.6968e-04);
  EXPECT_DOUBLE_EQ(src->sensors().imu.accel_random_walk, 3.0e-3);
  EXPECT_DOUBLE_EQ(src->imu()[3].gyro_rad_s.z(), 0.003);
  EXPECT_DOUBLE_EQ(src->imu()[3].accel_m_s2.z(), 9.81);

  const Frame f = src->readFrame(2);
  EXPECT_EQ(f.index, 2);
  EXPECT_EQ(f.t_ns, frameStamp(spec, 2));
  ASSERT_EQ(f.image.type(), CV_8UC1);
  EXPECT_EQ(cv::norm(f.image, testImage(spec, 2), cv::NORM_INF), 0.0);
  EXPECT_TRUE(std::isnan(f.exposure_ms));
  EXPECT_TRUE(src->sensors().photometric.vignette.empty());
}

TEST(EurocSource, AcceptsTheMav0FolderItself) {
  TempDir tmp;
  writeDataset(tmp.path(), DatasetSpec());
  auto src = makeSource();
  src->open((tmp.path() / "mav0").string());
  EXPECT_EQ(src->numFrames(), 5u);
}

TEST(EurocSource, ReadsTumViLayoutWithKalibrAndPhotometricCalibration) {
  TempDir tmp;
  DatasetSpec spec;
  spec.sensor_yaml = false;
  writeDataset(tmp.path(), spec);
  fs::remove(tmp.path() / "mav0" / "imu0" / "sensor.yaml");
  const Eigen::Isometry3d T_c_i = someTransform(3.0, {0.1, 1.0, 0.2}, {0.04, -0.07, -0.05});
  writeText(tmp.path() / "dso" / "camchain.yaml",
            kalibrCamera("cam0", 64, 48, "  T_cam_imu:\n" + kalibrMatrix(T_c_i, "  ")) +
                "  timeshift_cam_imu: 0.0012\n");
  writeText(tmp.path() / "dso" / "imu_config.yaml",
            "accelerometer_noise_density: 0.0028\naccelerometer_random_walk: 0.00086\n"
            "gyroscope_noise_density: 0.00016\ngyroscope_random_walk: 2.2e-05\nrostopic: /imu0\nupdate_rate: 200.0\n");
  std::string pcalib;
  for (int k = 0; k < 256; ++k) pcalib += std::to_string(k * k * 0.003 + k) + " ";
  writeText(tmp.path() / "dso" / "cam0" / "pcalib.txt", pcalib + "\n");
  cv::Mat vig(48, 64, CV_8UC1, cv::Scalar(100));
  vig.at<uint8_t>(24, 32) = 200;
  cv::imwrite((tmp.path() / "dso" / "cam0" / "vignette.png").string(), vig);
  std::string times;
  for (int i = 0; i < 4; ++i) {  // no exposure for the last frame
    char buf[96];
    std::snprintf(buf, sizeof(buf), "%lld %.9f %.3f\n", static_cast<long long>(frameStamp(spec, i)),
                  frameStamp(spec, i) * 1e-9, 2.0 + i);
    times += buf;
  }
  writeText(tmp.path() / "dso" / "cam0" / "times.txt", times);

  auto src = makeSource();
  src->open(tmp.str());
  const CameraCalibration& c = src->sensors().camera;
  EXPECT_EQ(c.distortion, "equidistant");
  EXPECT_DOUBLE_EQ(c.intrinsics[2], 25.493170605935475);
  EXPECT_DOUBLE_EQ(c.time_offset_s, 0.0012);
  expectIsometryNear(c.T_B_C, T_c_i.inverse(), 1e-12);  // T_B_C = T_cam_imu^-1
  EXPECT_NEAR(c.rate_hz, 20.0, 1e-9);                    // from the stamps: Kalibr has no rate
  EXPECT_DOUBLE_EQ(src->sensors().imu.accel_noise_density, 0.0028);
  EXPECT_DOUBLE_EQ(src->sensors().imu.rate_hz, 200.0);

  const PhotometricCalibration& ph = src->sensors().photometric;
  ASSERT_EQ(ph.inverse_response.size(), 256u);
  EXPECT_FLOAT_EQ(ph.inverse_response[10], 10.3f);
  ASSERT_EQ(ph.vignette.type(), CV_32FC1);
  EXPECT_FLOAT_EQ(ph.vignette.at<float>(24, 32), 1.0f);
  EXPECT_FLOAT_EQ(ph.vignette.at<float>(0, 0), 0.5f);
  EXPECT_DOUBLE_EQ(src->readFrame(1).exposure_ms, 3.0);
  EXPECT_TRUE(std::isnan(src->readFrame(4).exposure_ms));
  EXPECT_TRUE(anyContains(src->warnings(), "no exposure time for 1 of 5 frames")) << joined(src->warnings());
}

// The TUM RS-VIO layout: cam0 global shutter and cam1 rolling shutter side by side, 16-bit PNGs, one
// Kalibr camchain for both (TUM's camchain-calibration-equidistant4_camimu_dataset-calib-imu1.yaml),
// image stamps of the first row read out.
TEST(EurocSource, ReadsTumRsLayoutRollingShutterCameraWithFirstRowStamps) {
  TempDir tmp;
  DatasetSpec gs;
  gs.sixteen_bit = true;
  gs.sensor_yaml = false;
  DatasetSpec rs = gs;
  rs.camera = "cam1";
  rs.imu = false;
  writeDataset(tmp.path(), gs);
  writeDataset(tmp.path(), rs);
  const Eigen::Isometry3d T_c0_i = someTransform(3.1, {0.0, 0.0, 1.0}, {0.007, -0.057, -0.042});
  const Eigen::Isometry3d T_c1_i = someTransform(3.0, {0.0, 0.1, 1.0}, {-0.05, -0.057, -0.042});
  writeText(tmp.path() / "camchain-calibration-equidistant4_camimu_dataset-calib-imu1.yaml",
            kalibrCamera("cam0", 64, 48, "  T_cam_imu:\n" + kalibrMatrix(T_c0_i, "  ")) +
                kalibrCamera("cam1", 64, 48, "  T_cam_imu:\n" + kalibrMatrix(T_c1_i, "  ")));

  auto src = makeSource({{"camera", "cam1"}, {"timestamp_row", "first"}, {"line_delay_us", 29.4737}});
  src->open(tmp.str());
  // t_mid = t_first + y0 * line_delay, y0 = (48 - 1) / 2.
  const int64_t shift = std::llround(23.5 * 29.4737e-6 * 1e9);
  EXPECT_EQ(shift, 692632);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(src->frameTime(i), frameStamp(rs, i) + shift);
  expectIsometryNear(src->sensors().camera.T_B_C, T_c1_i.inverse(), 1e-12);
  // The calibration holds no line delay: the param converts stamps, the shutter plugin models rows.
  EXPECT_EQ(src->sensors().camera.line_delay_s, 0.0);
  const Frame f = src->readFrame(3);
  ASSERT_EQ(f.image.type(), CV_16UC1);
  EXPECT_EQ(cv::norm(f.image, testImage(rs, 3), cv::NORM_INF), 0.0);
  EXPECT_EQ(f.t_ns, frameStamp(rs, 3) + shift);
  EXPECT_TRUE(src->warnings().empty()) << joined(src->warnings());
}

TEST(EurocSource, WarnsWhenStampRowNeedsAnUnknownLineDelay) {
  TempDir tmp;
  DatasetSpec spec;
  writeDataset(tmp.path(), spec);
  auto src = makeSource({{"timestamp_row", "first"}});
  src->open(tmp.str());
  EXPECT_EQ(src->frameTime(0), frameStamp(spec, 0));  // left as stamped
  EXPECT_TRUE(anyContains(src->warnings(), "needs params.line_delay_us")) << joined(src->warnings());
}

TEST(EurocSource, LastRowStampsUseTheCalibrationsLineDelay) {
  TempDir tmp;
  DatasetSpec spec;
  writeDataset(tmp.path(), spec);
  writeText(tmp.path() / "mav0" / "cam0" / "sensor.yaml", eurocCameraYaml(64, 48, "line_delay_ns: 20000\n"));
  auto src = makeSource({{"timestamp_row", "last"}});
  src->open(tmp.str());
  EXPECT_DOUBLE_EQ(src->sensors().camera.line_delay_s, 20e-6);
  EXPECT_EQ(src->frameTime(1), frameStamp(spec, 1) - 470000);  // 23.5 rows * 20 us
}

TEST(EurocSource, ChainsKalibrCameraWithoutOwnImuExtrinsic) {
  TempDir tmp;
  DatasetSpec spec;
  spec.camera = "cam1";
  spec.sensor_yaml = false;
  writeDataset(tmp.path(), spec);
  const Eigen::Isometry3d T_c0_i = someTransform(0.3, {1, 2, 3}, {0.1, 0.2, 0.3});
  const Eigen::Isometry3d T_c1_c0 = someTransform(0.05, {0, 1, 0}, {-0.11, 0.0, 0.001});
  writeText(tmp.path() / "camchain.yaml",
            kalibrCamera("cam0", 64, 48, "  T_cam_imu:\n" + kalibrMatrix(T_c0_i, "  ")) +
                kalibrCamera("cam1", 64, 48, "  T_cn_cnm1:\n" + kalibrMatrix(T_c1_c0, "  ")));
  auto src = makeSource({{"camera", "cam1"}});
  src->open(tmp.str());
  expectIsometryNear(src->sensors().camera.T_B_C, (T_c1_c0 * T_c0_i).inverse(), 1e-12);
}

TEST(EurocSource, PrefersKalibrsCameraImuChainOverItsCameraOnlyChain) {
  TempDir tmp;
  DatasetSpec spec;
  spec.sensor_yaml = false;
  writeDataset(tmp.path(), spec);
  const Eigen::Isometry3d T_c_i = someTransform(0.2, {0, 0, 1}, {0.01, 0.02, 0.03});
  writeText(tmp.path() / "camchain-dataset-calib.yaml", kalibrCamera("cam0", 64, 48, ""));
  writeText(tmp.path() / "camchain-imucam-dataset-calib.yaml",
            kalibrCamera("cam0", 64, 48, "  T_cam_imu:\n" + kalibrMatrix(T_c_i, "  ")) + "  timeshift_cam_imu: -0.002\n");
  auto src = makeSource();
  src->open(tmp.str());
  expectIsometryNear(src->sensors().camera.T_B_C, T_c_i.inverse(), 1e-12);
  EXPECT_DOUBLE_EQ(src->sensors().camera.time_offset_s, -0.002);
}

TEST(EurocSource, ImageScaleResizesAndRescalesIntrinsicsAndLineDelay) {
  TempDir tmp;
  DatasetSpec spec;
  writeDataset(tmp.path(), spec);
  writeText(tmp.path() / "mav0" / "cam0" / "sensor.yaml", eurocCameraYaml(64, 48, "line_delay_us: 20\n"));
  auto src = makeSource({{"image_scale", 0.5}});
  src->open(tmp.str());
  const CameraCalibration& c = src->sensors().camera;
  EXPECT_EQ(c.width, 32);
  EXPECT_EQ(c.height, 24);
  EXPECT_DOUBLE_EQ(c.intrinsics[0], 0.5 * 45.8654);
  EXPECT_DOUBLE_EQ(c.intrinsics[2], 0.5 * (31.7215 + 0.5) - 0.5);
  EXPECT_DOUBLE_EQ(c.line_delay_s, 40e-6);  // the same readout time over half the rows
  // Frame times are those of the middle row, which resizing keeps.
  EXPECT_EQ(src->frameTime(0), frameStamp(spec, 0));
  const Frame f = src->readFrame(0);
  EXPECT_EQ(f.image.cols, 32);
  EXPECT_EQ(f.image.rows, 24);
  EXPECT_EQ(f.image.type(), CV_8UC1);
}

TEST(EurocSource, PrefersKalibrOverSensorYamlWithAWarningAndObeysTheParam) {
  TempDir tmp;
  DatasetSpec spec;
  writeDataset(tmp.path(), spec);
  writeText(tmp.path() / "dso" / "camchain.yaml", kalibrCamera("cam0", 64, 48, ""));
  auto src = makeSource();
  src->open(tmp.str());
  EXPECT_EQ(src->sensors().camera.distortion, "equidistant");
  EXPECT_TRUE(anyContains(src->warnings(), "is ignored (set params.calibration = \"euroc\"")) << joined(src->warnings());
  EXPECT_TRUE(anyContains(src->warnings(), "no T_cam_imu for 'cam0'")) << joined(src->warnings());

  auto euroc = makeSource({{"calibration", "euroc"}});
  euroc->open(tmp.str());
  EXPECT_EQ(euroc->sensors().camera.distortion, "radtan");

  auto file = makeSource({{"calibration_file", "dso/camchain.yaml"}});
  file->open(tmp.str());
  EXPECT_EQ(file->sensors().camera.distortion, "equidistant");
}

// Images are read on demand: a file removed after open() is noticed only by readFrame (streaming, no
// image kept in memory by the source).
TEST(EurocSource, ReadsImagesOnDemand) {
  TempDir tmp;
  DatasetSpec spec;
  writeDataset(tmp.path(), spec);
  auto src = makeSource();
  src->open(tmp.str());
  const fs::path img = tmp.path() / "mav0" / "cam0" / "data" / (std::to_string(frameStamp(spec, 3)) + ".png");
  fs::remove(img);
  EXPECT_NO_THROW(src->readFrame(2));
  const std::string msg = errorOf([&] { src->readFrame(3); });
  EXPECT_NE(msg.find("frame 3"), std::string::npos) << msg;
  EXPECT_NE(msg.find(std::to_string(frameStamp(spec, 3)) + " ns"), std::string::npos) << msg;
  EXPECT_NE(msg.find("image not found"), std::string::npos) << msg;
  EXPECT_NE(msg.find(img.string()), std::string::npos) << msg;
}

TEST(EurocSource, ParamTableRejectsBadValues) {
  PluginHost host({RSVIO_PLUGIN_DIR});
  std::vector<ConfigProblem> problems;
  validateParams({{"timestamp_row", "top"}, {"max_imu_gap_ms", -1}, {"camra", "cam1"}},
                 host.info("source.euroc").params, "source.params", problems);
  std::string all;
  for (const auto& p : problems) all += p.str() + "\n";
  EXPECT_EQ(problems.size(), 3u) << all;
  EXPECT_NE(all.find("source.params.timestamp_row"), std::string::npos) << all;
  EXPECT_NE(all.find("source.params.max_imu_gap_ms"), std::string::npos) << all;
  EXPECT_NE(all.find("camera"), std::string::npos) << all;  // did-you-mean
}
