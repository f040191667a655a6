// photometric_io.cpp: lights files, image lists, images and masks. Images are written by OpenCV
// or byte by byte (the Truevision TGA layout) and read back; malformed files are InputErrors
// naming the file, the line and the field; the common lights layouts, DiLiGenT's, and TGA
// files read like PNGs of the same pixels.

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/modeling/photometric.hpp"
#include "hapticlab/test/error_of.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::modeling::photometric_io_test {
namespace {

constexpr double kPi = 3.141592653589793;

template <class F>
std::string Message(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.diagnostics().at(0).message;
  }
  return "no error";
}

TEST(PhotometricIo, LightsWrittenAsAnglesReadBackAsUnitDirections) {
  test::TempDir dir;
  // Directions from elevation e above the sample plane and azimuth a from +x towards +y:
  // (cos e cos a, cos e sin a, sin e).
  std::string text = "# written by the test\nfile,elevation_deg,azimuth_deg\r\n";
  std::vector<Eigen::Vector3d> truth;
  for (int k = 0; k < 7; ++k) {
    const double e = 20 + 10 * k, a = -170 + 53 * k;
    text += fmt::format("img{}.png, {}, {}\r\n", k, e, a);
    const double er = e * kPi / 180, ar = a * kPi / 180;
    truth.emplace_back(std::cos(er) * std::cos(ar), std::cos(er) * std::sin(ar), std::sin(er));
  }
  test::WriteFile(dir.File("angles.csv"), text);
  const auto L = LoadLights(dir.File("angles.csv"));
  ASSERT_EQ(L.size(), truth.size());
  for (std::size_t k = 0; k < L.size(); ++k) {
    EXPECT_EQ(L[k].file, fmt::format("img{}.png", k));
    EXPECT_LT((L[k].direction - truth[k]).norm(), 1e-12) << k;
    EXPECT_EQ(L[k].line, static_cast<int>(k) + 3);
    EXPECT_EQ(L[k].source, dir.File("angles.csv"));
  }
  // y up: the same file mirrored in y.
  const auto up = LoadLights(dir.File("angles.csv"), /*y_up=*/true);
  for (std::size_t k = 0; k < L.size(); ++k)
    EXPECT_LT((up[k].direction - Eigen::Vector3d(truth[k].x(), -truth[k].y(), truth[k].z())).norm(),
              1e-12);
  // The dome preset mirrors too.
  const auto dome = LoadLights("dome"), dome_up = LoadLights("dome", true);
  ASSERT_EQ(dome.size(), 30u);
  EXPECT_EQ(dome_up[3].direction.y(), -dome[3].direction.y());
}

TEST(PhotometricIo, MalformedLightsFilesNameFileLineAndField) {
  test::TempDir dir;
  const auto at = [&](const std::string& name, const std::string& text) {
    test::WriteFile(dir.File(name), text);
    std::string w = test::WhereOf([&] { LoadLights(dir.File(name)); });
    if (w.rfind(dir.path() + "/", 0) == 0) w.erase(0, dir.path().size() + 1);
    return w;
  };
  EXPECT_EQ(at("nan.txt", "a.png 0 0 1\nb.png nan 0 1\nc.png 0 1 1\n"), "nan.txt|2|lx");
  EXPECT_EQ(at("inf.txt", "0 0 1\n1 0 1\n0 1 inf\n"), "inf.txt|3|lz");
  EXPECT_EQ(at("zero.txt", "0 0 1\n0 0 0\n0 1 1\n"), "zero.txt|2|lx");
  EXPECT_EQ(at("azimuth.txt", "a.png 40 0\nb.png 40 east\nc.png 40 180\n"),
            "azimuth.txt|2|azimuth_deg");
  EXPECT_EQ(at("below.txt", "0 0 1\n1 0 1\n0 1 -0.01\n"), "below.txt|3|lz");
  // Structure errors name the line; there is no single field to blame.
  EXPECT_EQ(at("comma.csv", "a.png,0,,1\nb.png,1,0,1\nc.png,0,1,1\n"), "comma.csv|1|");
  EXPECT_EQ(at("trailing.csv", "a.png,0,0,1\nb.png,1,0,1,\nc.png,0,1,1\n"), "trailing.csv|2|");
  EXPECT_EQ(at("shape.txt", "\n\na.png 0 0 1 9 9\n"), "shape.txt|3|");
  EXPECT_EQ(at("two.txt", "0 0 1\n1 0 1\n"), "two.txt|0|");
  EXPECT_EQ(Message([&] { LoadLights(dir.File("two.txt")); }),
            "photometric stereo needs at least 3 lights");
  EXPECT_NE(Message([&] { LoadLights(dir.File("comma.csv")); }).find("empty cell"),
            std::string::npos);
  EXPECT_EQ(
      test::WhereOf([&] { LoadLights(dir.File("missing.txt")); }).find(dir.File("missing.txt")),
      0u);
}

TEST(PhotometricIo, LightsFilesAndImageHeadersAreBoundedBeforeAllocation) {
  test::TempDir dir;
  const auto at = [&](const std::string& name, const std::string& text) {
    test::WriteFile(dir.File(name), text);
    std::string w = test::WhereOf([&] { LoadLights(dir.File(name)); });
    if (w.rfind(dir.path() + "/", 0) == 0) w.erase(0, dir.path().size() + 1);
    return w;
  };
  // One NUL byte crashed the reader (cells[0] of an empty line); a count past the bound was
  // std::stoul's out_of_range.
  EXPECT_EQ(at("nul.txt", std::string(1, '\0')), "nul.txt|1|");
  EXPECT_EQ(at("count.txt", "99999999999999999999999\n0 0 1\n"), "count.txt|1|count");
  EXPECT_EQ(at("count2.txt", "2000\n0 0 1\n"), "count2.txt|1|count");
  std::string many;
  for (std::size_t i = 0; i <= kMaxLights; ++i) many += "0 0.1 1\n";
  EXPECT_NE(Message([&] {
              at("many.txt", many);
              LoadLights(dir.File("many.txt"));
            }).find("at most 1024"),
            std::string::npos);
  // A TGA header claiming 65535 x 65535 RLE pixels in 576 bytes: refused before the 17 GB.
  std::string tga(18, '\0');
  tga[2] = 10;  // RLE colour
  tga[12] = tga[13] = tga[14] = tga[15] = static_cast<char>(0xFF);
  tga[16] = 32;
  tga += std::string(576, '\x7f');
  test::WriteFile(dir.File("big.tga"), tga);
  int w = 0, h = 0;
  EXPECT_NE(Message([&] { ReadGreyImage(dir.File("big.tga"), &w, &h); }).find("RLE data truncated"),
            std::string::npos);
  tga[2] = 2;  // the same claim, uncompressed
  test::WriteFile(dir.File("raw.tga"), tga);
  EXPECT_NE(
      Message([&] { ReadGreyImage(dir.File("raw.tga"), &w, &h); }).find("pixel data truncated"),
      std::string::npos);
}

TEST(PhotometricIo, ImageListsNameTheLineOfAMalformedEntry) {
  test::TempDir dir;
  test::WriteFile(dir.File("l.txt"), "0 0 1\n1 0 1\n0 1 1\n");
  auto L = LoadLights(dir.File("l.txt"));
  test::WriteFile(dir.File("list.txt"), "# images\na.png\nb c.png\nd.png\n");
  EXPECT_EQ(test::WhereOf([&] { ApplyImageList(dir.File("list.txt"), L); }),
            dir.File("list.txt") + "|3|");
  EXPECT_TRUE(L[0].file.empty()) << "nothing applied on error";
  // Without names, reading the images names the lights file, the light's line and "file".
  EXPECT_EQ(test::WhereOf([&] { ReadImages(dir.path(), L); }), dir.File("l.txt") + "|1|file");
}

// A w x h test pattern with distinct values per pixel (row-major).
cv::Mat Pattern(int w, int h, int type, double scale) {
  cv::Mat m(h, w, type);
  for (int i = 0; i < h; ++i)
    for (int j = 0; j < w; ++j) {
      const double v = scale * (1 + i * w + j) / (w * h + 1);
      for (int c = 0; c < m.channels(); ++c) {
        const double x = m.channels() == 1 ? v : scale * (0.2 + 0.25 * c) * (1 + ((i + j + c) % 3));
        if (m.depth() == CV_8U)
          m.ptr<unsigned char>(i)[j * m.channels() + c] = cv::saturate_cast<unsigned char>(x);
        else if (m.depth() == CV_16U)
          m.ptr<std::uint16_t>(i)[j * m.channels() + c] = cv::saturate_cast<std::uint16_t>(x);
        else
          m.ptr<float>(i)[j * m.channels() + c] = static_cast<float>(x);
      }
    }
  return m;
}

// The grey value the reader must return: [0, 1] for integers, BT.601 luma for colour.
double Expected(const cv::Mat& m, int i, int j) {
  const double s = m.depth() == CV_8U ? 255 : m.depth() == CV_16U ? 65535 : 1;
  const auto px = [&](int c) {
    return m.depth() == CV_8U    ? m.ptr<unsigned char>(i)[j * m.channels() + c] / s
           : m.depth() == CV_16U ? m.ptr<std::uint16_t>(i)[j * m.channels() + c] / s
                                 : m.ptr<float>(i)[j * m.channels() + c];
  };
  if (m.channels() == 1) return px(0);
  return 0.114 * px(0) + 0.587 * px(1) + 0.299 * px(2);  // OpenCV stores B, G, R(, A)
}

TEST(PhotometricIo, ImagesWrittenByOpenCvReadBackAsGreyInTheirStoredOrder) {
  test::TempDir dir;
  const int w = 7, h = 5;
  const std::vector<std::pair<std::string, cv::Mat>> cases = {
      {"g8.png", Pattern(w, h, CV_8UC1, 255)},    {"g16.png", Pattern(w, h, CV_16UC1, 65535)},
      {"c8.png", Pattern(w, h, CV_8UC3, 100)},    {"a8.png", Pattern(w, h, CV_8UC4, 100)},
      {"f32.tiff", Pattern(w, h, CV_32FC1, 3.0)}, {"c16.tiff", Pattern(w, h, CV_16UC3, 20000)}};
  for (const auto& [name, img] : cases) {
    ASSERT_TRUE(cv::imwrite(dir.File(name), img)) << name;
    int ww = 0, hh = 0;
    const auto g = ReadGreyImage(dir.File(name), &ww, &hh);
    ASSERT_EQ(ww, w) << name;
    ASSERT_EQ(hh, h) << name;
    for (int i = 0; i < h; ++i)
      for (int j = 0; j < w; ++j)
        EXPECT_NEAR(g[static_cast<std::size_t>(i * w + j)], Expected(img, i, j), 5e-6)
            << name << " at row " << i << ", column " << j;
  }
  // Values above 1 in float images are kept (radiance, not clipped).
  int ww = 0, hh = 0;
  EXPECT_GT(ReadGreyImage(dir.File("f32.tiff"), &ww, &hh).back(), 2.0f);
  // A stack of images must agree in size; the offending file is named.
  ASSERT_TRUE(cv::imwrite(dir.File("small.png"), Pattern(w - 1, h, CV_8UC1, 255)));
  std::vector<Light> lights = LoadLights("dome");
  lights.resize(3);
  lights[0].file = "g8.png", lights[1].file = "c8.png", lights[2].file = "small.png";
  EXPECT_EQ(test::WhereOf([&] { ReadImages(dir.path(), lights); }), dir.File("small.png") + "|0|");
  lights[2].file = "nope.png";
  EXPECT_EQ(Message([&] { ReadImages(dir.path(), lights); }), "image not found");
  test::WriteFile(dir.File("text.png"), "not an image");
  EXPECT_EQ(test::WhereOf([&] { ReadGreyImage(dir.File("text.png"), &ww, &hh); }),
            dir.File("text.png") + "|0|");
  lights[2].file = "g16.png";
  const auto stack = ReadImages(dir.path(), lights);
  ASSERT_EQ(stack.images.size(), 3u);
  EXPECT_EQ(stack.width, w);
  EXPECT_EQ(stack.height, h);
}

TEST(PhotometricIo, MaskIsAnyNonZeroColourChannelWithAlphaIgnored) {
  test::TempDir dir;
  cv::Mat m(2, 3, CV_8UC4, cv::Scalar(0, 0, 0, 255));  // opaque black: outside
  m.at<cv::Vec4b>(0, 1) = {0, 0, 9, 0};                // red only, transparent: inside
  m.at<cv::Vec4b>(1, 2) = {1, 0, 0, 255};              // faint blue: inside
  ASSERT_TRUE(cv::imwrite(dir.File("mask.png"), m));
  const auto mask = ReadMask(dir.File("mask.png"), 3, 2);
  EXPECT_EQ(mask, (std::vector<std::uint8_t>{0, 1, 0, 0, 0, 1}));
  EXPECT_EQ(test::WhereOf([&] { ReadMask(dir.File("mask.png"), 2, 3); }),
            dir.File("mask.png") + "|0|");
  EXPECT_NE(Message([&] { ReadMask(dir.File("mask.png"), 2, 3); }).find("mask is 3x2"),
            std::string::npos);
}

// TGA bytes: header, then pixels given in file order.
std::vector<unsigned char> Tga(int type, int bpp, int desc, int w, int h,
                               const std::vector<unsigned char>& pixels) {
  std::vector<unsigned char> f(18, 0);
  f[2] = static_cast<unsigned char>(type);
  f[12] = static_cast<unsigned char>(w), f[14] = static_cast<unsigned char>(h);
  f[16] = static_cast<unsigned char>(bpp), f[17] = static_cast<unsigned char>(desc);
  for (const unsigned char p : pixels) f.push_back(p);
  return f;
}

std::vector<float> ReadTga(const test::TempDir& dir, const std::vector<unsigned char>& bytes,
                           int* w, int* h) {
  std::ofstream(dir.File("t.tga"), std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));
  return ReadGreyImage(dir.File("t.tga"), w, h);
}

TEST(PhotometricIo, TgaVariantsAndTruncatedFiles) {
  test::TempDir dir;
  int w = 0, h = 0;
  // 16-bit 5-5-5 colour, top-left origin, right to left: pixel (0, 0) is the second stored.
  // Stored: pure blue (31), then pure red (31 << 10).
  const auto c16 = ReadTga(dir, Tga(2, 16, 0x20 | 0x10, 2, 1, {31, 0, 0x00, 0x7c}), &w, &h);
  ASSERT_EQ(w, 2);
  ASSERT_EQ(h, 1);
  EXPECT_NEAR(c16[0], 0.299, 1e-3);  // red
  EXPECT_NEAR(c16[1], 0.114, 1e-3);  // blue
  // 32-bit BGRA, bottom-left origin: the first stored row is the bottom one; alpha ignored.
  const auto c32 = ReadTga(dir, Tga(2, 32, 8, 1, 2, {0, 255, 0, 0, 0, 0, 255, 255}), &w, &h);
  EXPECT_NEAR(c32[0], 0.299, 1e-3);  // top: the second stored pixel, red
  EXPECT_NEAR(c32[1], 0.587, 1e-3);  // bottom: green
  // Grey RLE (type 11): a run of three 51s, then two raw pixels.
  const auto g = ReadTga(dir, Tga(11, 8, 0x20, 5, 1, {0x82, 51, 0x01, 0, 255}), &w, &h);
  const float want[5] = {0.2f, 0.2f, 0.2f, 0.0f, 1.0f};
  ASSERT_EQ(g.size(), 5u);
  for (int k = 0; k < 5; ++k) EXPECT_NEAR(g[static_cast<std::size_t>(k)], want[k], 1e-6) << k;
  // Damaged files: the reader names the file and says what is wrong.
  const std::string t = dir.File("t.tga") + "|0|";
  const std::vector<std::pair<std::vector<unsigned char>, std::string>> bad = {
      {Tga(11, 8, 0x20, 5, 1, {0x85, 51}), "TGA: RLE packet runs past the image"},
      {Tga(11, 8, 0x20, 5, 1, {0x81, 51, 0x02, 0}), "TGA: RLE data truncated"},
      {Tga(1, 8, 0, 1, 1, {0}), "TGA: image type 1 not supported"},
      {Tga(3, 16, 0, 1, 1, {0, 0}), "TGA: 16 bits per pixel not supported for grey images"},
      {Tga(2, 24, 0, 0, 1, {}), "TGA: zero width or height"},
      {{0, 0, 2}, "TGA: file shorter than its 18-byte header"}};
  for (const auto& [bytes, what] : bad) {
    EXPECT_EQ(test::WhereOf([&] { ReadTga(dir, bytes, &w, &h); }), t) << what;
    EXPECT_EQ(Message([&] { ReadTga(dir, bytes, &w, &h); }).find(what), 0u)
        << Message([&] { ReadTga(dir, bytes, &w, &h); });
  }
}

std::string LightsError(const std::string& path) {
  try {
    LoadLights(path);
  } catch (const InputError& e) {
    const auto& d = e.diagnostics().at(0);
    return fmt::format("{}|{}", d.line, d.field);
  }
  return "no error";
}

TEST(Photometric, LightsFilesInTheCommonLayouts) {
  test::TempDir dir;
  const std::vector<std::pair<std::string, std::string>> files = {
      {"csv_header.csv", "file,lx,ly,lz\na.png,0,0,1\nb.png,1,0,1\nc.png,0,1,1\n"},
      {"count_spaces.txt", "3\na.png 0 0 1\nb.png   1 0 1\n\n# comment\nc.png\t0 1 1\r\n"},
      {"angles.txt", "file elevation_deg azimuth_deg\na.png 90 0\nb.png 45 0\nc.png, 45, 90\n"},
      {"csv_plain.csv", "a.png,0,0,2\nb.png,2,0,2\nc.png,0,3,3"},
  };
  for (const auto& [name, text] : files) {
    test::WriteFile(dir.File(name), text);
    const auto L = LoadLights(dir.File(name));
    ASSERT_EQ(L.size(), 3u) << name;
    EXPECT_EQ(L[2].file, "c.png") << name;
    EXPECT_LT((L[0].direction - Eigen::Vector3d(0, 0, 1)).norm(), 1e-12) << name;
    EXPECT_LT((L[1].direction - Eigen::Vector3d(1, 0, 1).normalized()).norm(), 1e-12) << name;
    EXPECT_LT((L[2].direction - Eigen::Vector3d(0, 1, 1).normalized()).norm(), 1e-12) << name;
  }
  EXPECT_EQ(LoadLights(dir.File("count_spaces.txt"))[2].line, 6);
  // DiLiGenT's layout: directions only, names from a list; y up.
  test::WriteFile(dir.File("light_directions.txt"), "0 0 1\n1 0 1\n0 -1 1\n");
  test::WriteFile(dir.File("filenames.txt"), "001.png\n002.png\n003.png\n");
  auto L = LoadLights(dir.File("light_directions.txt"), /*y_up=*/true);
  EXPECT_TRUE(L[0].file.empty());
  ApplyImageList(dir.File("filenames.txt"), L);
  EXPECT_EQ(L[1].file, "002.png");
  EXPECT_LT((L[2].direction - Eigen::Vector3d(0, 1, 1).normalized()).norm(), 1e-12);
  test::WriteFile(dir.File("short_list.txt"), "001.png\n002.png\n");
  EXPECT_THROW(ApplyImageList(dir.File("short_list.txt"), L), InputError);
  // Errors name the right line and field, with or without a count line or header.
  test::WriteFile(dir.File("e1.txt"), "3\na.png 0 0 1\nb.png 1 x 1\nc.png 0 1 1\n");
  EXPECT_EQ(LightsError(dir.File("e1.txt")), "3|ly");
  test::WriteFile(dir.File("e2.csv"), "a.png,0,0,1\nb.png,0,0,-1\nc.png,0,1,1\n");
  EXPECT_EQ(LightsError(dir.File("e2.csv")), "2|lz");
  test::WriteFile(dir.File("e3.txt"), "4\na.png 0 0 1\nb.png 1 0 1\nc.png 0 1 1\n");
  EXPECT_EQ(LightsError(dir.File("e3.txt")), "1|");
  test::WriteFile(dir.File("e4.txt"),
                  "# rig B\nfile,lx,ly,lz\na.png,0,0,1\nb.png,1,0,1\nc.png,0,1\n");
  EXPECT_EQ(LightsError(dir.File("e4.txt")), "5|");
  test::WriteFile(dir.File("e5.txt"), "file,x,y,z\na.png,0,0,1\n");
  EXPECT_EQ(LightsError(dir.File("e5.txt")), "1|file");
  test::WriteFile(dir.File("e6.txt"), "a.png 40 0\nb.png -5 90\nc.png 40 180\n");
  EXPECT_EQ(LightsError(dir.File("e6.txt")), "2|elevation_deg");
}

void WriteBytes(const std::string& path, const std::vector<unsigned char>& b) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  std::fwrite(b.data(), 1, b.size(), f);
  std::fclose(f);
}

TEST(Photometric, TgaImagesReadLikeThePngsOfTheSamePixels) {
  test::TempDir dir;
  const int w = 5, h = 4;
  // Grey, uncompressed, bottom-left origin (rows stored bottom first).
  cv::Mat grey(h, w, CV_8U);
  for (int i = 0; i < h; ++i)
    for (int j = 0; j < w; ++j)
      grey.at<unsigned char>(i, j) = static_cast<unsigned char>(40 * i + 7 * j + 3);
  std::vector<unsigned char> g;
  for (int i = h - 1; i >= 0; --i)
    for (int j = 0; j < w; ++j) g.push_back(grey.at<unsigned char>(i, j));
  WriteBytes(dir.File("g.tga"), Tga(3, 8, 0, w, h, g));
  ASSERT_TRUE(cv::imwrite(dir.File("g.png"), grey));
  // Colour, RLE, top-left origin: row 0 one run of 5 equal pixels, then raw packets.
  cv::Mat colour(h, w, CV_8UC3);
  std::vector<unsigned char> rle = {0x84, 10, 200, 90};
  for (int j = 0; j < w; ++j) colour.at<cv::Vec3b>(0, j) = cv::Vec3b(10, 200, 90);
  for (int i = 1; i < h; ++i) {
    rle.push_back(static_cast<unsigned char>(w - 1));
    for (int j = 0; j < w; ++j) {
      const cv::Vec3b px(static_cast<unsigned char>(30 * j), static_cast<unsigned char>(60 * i),
                         static_cast<unsigned char>(5 * i * j));
      colour.at<cv::Vec3b>(i, j) = px;
      rle.insert(rle.end(), {px[0], px[1], px[2]});
    }
  }
  WriteBytes(dir.File("c.tga"), Tga(10, 24, 0x20, w, h, rle));
  ASSERT_TRUE(cv::imwrite(dir.File("c.png"), colour));
  for (const std::string base : {"g", "c"}) {
    int w1 = 0, h1 = 0, w2 = 0, h2 = 0;
    const auto a = ReadGreyImage(dir.File(base + ".tga"), &w1, &h1),
               b = ReadGreyImage(dir.File(base + ".png"), &w2, &h2);
    ASSERT_EQ(w1, w);
    ASSERT_EQ(h1, h);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t k = 0; k < a.size(); ++k) EXPECT_EQ(a[k], b[k]) << base << " pixel " << k;
  }
  // A truncated file is an input error naming it.
  auto bytes = Tga(3, 8, 0, w, h, g);
  bytes.resize(bytes.size() - 3);
  WriteBytes(dir.File("t.tga"), bytes);
  int ww = 0, hh = 0;
  EXPECT_THROW(ReadGreyImage(dir.File("t.tga"), &ww, &hh), InputError);
}

}  // namespace
}  // namespace hapticlab::modeling::photometric_io_test
