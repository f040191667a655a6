// The hand-written XDF 1.0 writer (db/src/xdf_writer.cpp), read back by libxdf (Debian's
// libxdf-dev), a reader this project did not write: chunk lengths and sample counts in each
// of the variable-length widths, deduced timestamps, string markers, XML escaping.

#include "../../db/src/xdf_writer.hpp"

#include <gtest/gtest.h>
#include <xdf.h>

#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "hapticlab/core/status.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::db::internal::xdf_writer_test {
namespace {

std::string FloatInfo(const std::string& name, int channels, double rate_hz) {
  return "<name>" + name + "</name><type>Force</type><channel_count>" + std::to_string(channels) +
         "</channel_count><nominal_srate>" + std::to_string(rate_hz) +
         "</nominal_srate><channel_format>float32</channel_format>";
}

TEST(XdfWriter, XmlEscapeCoversTheFiveEntities) {
  EXPECT_EQ(XmlEscape("a<b & \"c\" 'd'>"), "a&lt;b &amp; &quot;c&quot; &apos;d&apos;&gt;");
  EXPECT_EQ(XmlEscape("plain"), "plain");
}

TEST(XdfWriter, FloatAndStringStreamsReadBackByLibxdf) {
  test::TempDir dir;
  const std::string path = dir.File("w.xdf");
  // 300 samples of 2 channels in one chunk: a count above 255 takes the 4-byte varlen and the
  // chunk (2.4 kB) a 4-byte length; a second chunk of 3 samples the 1-byte forms.
  std::vector<float> a;
  for (int i = 0; i < 300; ++i) {
    a.push_back(static_cast<float>(i));
    a.push_back(-0.5f * static_cast<float>(i));
  }
  const std::vector<float> b = {1000, 1, 1001, 2, 1002, 3};
  std::vector<std::string> marks = {"trial <1> & \"go\"", "", std::string(300, 'x')};
  {
    XdfWriter w(path);
    w.StreamHeader(1, FloatInfo("force & more", 2, 1000));
    w.StreamHeader(2,
                   "<name>events</name><type>Markers</type><channel_count>1</channel_count>"
                   "<nominal_srate>0</nominal_srate><channel_format>string</channel_format>");
    w.FloatSamples(1, 2, a.data(), 300, 10.0);
    w.FloatSamples(1, 2, b.data(), 0, 99.0);  // nothing: no chunk
    w.StringSamples(2, marks, {10.0, 10.25, 12.5});
    w.FloatSamples(1, 2, b.data(), 3, 20.0);
    w.StreamFooter(1, "<first_timestamp>10</first_timestamp><sample_count>303</sample_count>");
    w.StreamFooter(2, "<sample_count>3</sample_count>");
    w.Close();
  }
  Xdf x;
  ASSERT_EQ(x.load_xdf(path), 0);
  ASSERT_EQ(x.streams.size(), 2u);
  std::map<std::string, const Xdf::Stream*> by;
  for (const auto& s : x.streams) by[s.info.name] = &s;
  ASSERT_TRUE(by.contains("force & more")) << "the header's XML was not read back";
  const auto& f = *by.at("force & more");
  EXPECT_EQ(f.info.channel_count, 2);
  EXPECT_EQ(f.info.nominal_srate, 1000);
  ASSERT_EQ(f.time_stamps.size(), 303u);
  ASSERT_EQ(f.time_series.size(), 2u);
  for (std::size_t i = 0; i < 300; ++i) {
    EXPECT_EQ(f.time_series[0][i], static_cast<float>(i));
    EXPECT_EQ(f.time_series[1][i], -0.5f * static_cast<float>(i));
    // Left out timestamps are the previous one + 1 / nominal rate.
    EXPECT_NEAR(f.time_stamps[i], 10.0 + 1e-3 * static_cast<double>(i), 1e-9) << i;
  }
  EXPECT_EQ(f.time_stamps[300], 20.0);
  EXPECT_NEAR(f.time_stamps[302], 20.002, 1e-9);
  EXPECT_EQ(f.time_series[0][302], 1002.0f);
  EXPECT_EQ(f.time_series[1][301], 2.0f);
  // String samples are markers in libxdf's event map, each with its own timestamp.
  std::vector<std::pair<std::string, double>> got;
  for (const auto& [ev, stream] : x.eventMap) got.push_back(ev);
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got[0].first, marks[0]);
  EXPECT_EQ(got[0].second, 10.0);
  EXPECT_EQ(got[1].first, "");
  EXPECT_EQ(got[1].second, 10.25);
  EXPECT_EQ(got[2].first, marks[2]);  // a 300-byte string: 4-byte length
  EXPECT_EQ(got[2].second, 12.5);
}

TEST(XdfWriter, BadPathAndMismatchedTimestampsAreRefused) {
  test::TempDir dir;
  try {
    XdfWriter w(dir.File("missing/dir/w.xdf"));
    ADD_FAILURE() << "a file in a missing folder was opened";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("missing/dir/w.xdf"), std::string::npos) << e.what();
  }
  XdfWriter w(dir.File("w.xdf"));
  EXPECT_THROW(w.StringSamples(1, {"a", "b"}, {1.0}), PreconditionError);
}

}  // namespace
}  // namespace hapticlab::db::internal::xdf_writer_test
