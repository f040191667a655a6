#pragma once
// A writer of XDF 1.0 files (the Lab Streaming Layer's file format,
// https://github.com/sccn/xdf/wiki/Specifications). Written here by hand because no Debian
// package writes XDF: libxdf (libxdf-dev) only reads it (the tests use it to read our files
// back), and liblsl's recorder (LabRecorder) is an application, not a library, and not
// packaged. The format is a magic code and a sequence of chunks:
//   [NumLengthBytes: 1|4|8][Length: that many bytes, little-endian][Tag: uint16][Content]
// where Length counts the tag and the content. Tags: 1 FileHeader (XML), 2 StreamHeader
// (uint32 id + XML), 3 Samples (uint32 id + varlen count + samples), 6 StreamFooter
// (uint32 id + XML). A sample is [TimeStampBytes: 0|8][double timestamp][values]; a
// timestamp left out (0 bytes) is the previous one plus 1 / nominal rate. Strings are
// [varlen length][bytes]. All numbers little-endian (this writer requires a little-endian
// host, checked at compile time).

#include <bit>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

namespace hapticlab::db::internal {

static_assert(std::endian::native == std::endian::little,
              "the XDF writer assumes a little-endian host");

/// Escapes &, <, >, " and ' for XML text.
std::string XmlEscape(const std::string& s);

class XdfWriter {
 public:
  /// Opens `path` and writes the magic code and the file header. Throws std::runtime_error
  /// naming the file when it cannot be written.
  explicit XdfWriter(const std::string& path);
  /// Stream header: `info_xml` is the content of <info> (name, type, channel_count,
  /// nominal_srate, channel_format, desc...), without the <info> element itself.
  void StreamHeader(std::uint32_t id, const std::string& info_xml);
  /// float32 samples (row-major, `channels` per sample); the first carries `t0_s`, the rest
  /// are deduced by readers from the nominal rate.
  void FloatSamples(std::uint32_t id, std::size_t channels, const float* samples, std::size_t count,
                    double t0_s);
  /// One-channel string samples, each with its own timestamp.
  void StringSamples(std::uint32_t id, const std::vector<std::string>& values,
                     const std::vector<double>& t_s);
  void StreamFooter(std::uint32_t id, const std::string& info_xml);
  /// Flushes and closes; throws naming the file on failure.
  void Close();

 private:
  void Chunk(std::uint16_t tag, const std::string& content);
  std::string path_;
  std::ofstream f_;
};

}  // namespace hapticlab::db::internal
