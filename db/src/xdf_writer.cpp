#include "xdf_writer.hpp"

#include <cstring>
#include <stdexcept>

#include "hapticlab/core/status.hpp"

namespace hapticlab::db::internal {
namespace {

template <typename T>
void Put(std::string* out, T v) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  out->append(b, sizeof(T));
}

// Variable-length integer: [NumBytes 1|4|8][value].
void PutVarLen(std::string* out, std::uint64_t v) {
  if (v <= 0xFFu) {
    Put<std::uint8_t>(out, 1);
    Put<std::uint8_t>(out, static_cast<std::uint8_t>(v));
  } else if (v <= 0xFFFFFFFFu) {
    Put<std::uint8_t>(out, 4);
    Put<std::uint32_t>(out, static_cast<std::uint32_t>(v));
  } else {
    Put<std::uint8_t>(out, 8);
    Put<std::uint64_t>(out, v);
  }
}

}  // namespace

std::string XmlEscape(const std::string& s) {
  std::string o;
  o.reserve(s.size());
  for (const char c : s) {
    switch (c) {
      case '&':
        o += "&amp;";
        break;
      case '<':
        o += "&lt;";
        break;
      case '>':
        o += "&gt;";
        break;
      case '"':
        o += "&quot;";
        break;
      case '\'':
        o += "&apos;";
        break;
      default:
        o += c;
    }
  }
  return o;
}

XdfWriter::XdfWriter(const std::string& path)
    : path_(path), f_(path, std::ios::binary | std::ios::trunc) {
  if (!f_) throw std::runtime_error(path + ": cannot write");
  f_.write("XDF:", 4);
  Chunk(1, "<?xml version=\"1.0\"?><info><version>1.0</version></info>");
}

void XdfWriter::Chunk(std::uint16_t tag, const std::string& content) {
  std::string head;
  PutVarLen(&head, content.size() + 2);
  Put<std::uint16_t>(&head, tag);
  f_.write(head.data(), static_cast<std::streamsize>(head.size()));
  f_.write(content.data(), static_cast<std::streamsize>(content.size()));
  if (!f_) throw std::runtime_error(path_ + ": write failed");
}

void XdfWriter::StreamHeader(std::uint32_t id, const std::string& info_xml) {
  std::string c;
  Put<std::uint32_t>(&c, id);
  c += "<?xml version=\"1.0\"?><info>" + info_xml + "</info>";
  Chunk(2, c);
}

void XdfWriter::FloatSamples(std::uint32_t id, std::size_t channels, const float* samples,
                             std::size_t count, double t0_s) {
  if (count == 0) return;
  std::string c;
  c.reserve(16 + count * (1 + channels * sizeof(float)) + 8);
  Put<std::uint32_t>(&c, id);
  PutVarLen(&c, count);
  for (std::size_t i = 0; i < count; ++i) {
    if (i == 0) {
      Put<std::uint8_t>(&c, 8);
      Put<double>(&c, t0_s);
    } else {
      Put<std::uint8_t>(&c, 0);
    }
    c.append(reinterpret_cast<const char*>(samples + i * channels), channels * sizeof(float));
  }
  Chunk(3, c);
}

void XdfWriter::StringSamples(std::uint32_t id, const std::vector<std::string>& values,
                              const std::vector<double>& t_s) {
  if (values.empty()) return;
  HL_REQUIRE(values.size() == t_s.size(), "XdfWriter::StringSamples: one timestamp per value");
  std::string c;
  Put<std::uint32_t>(&c, id);
  PutVarLen(&c, values.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    Put<std::uint8_t>(&c, 8);
    Put<double>(&c, t_s[i]);
    PutVarLen(&c, values[i].size());
    c += values[i];
  }
  Chunk(3, c);
}

void XdfWriter::StreamFooter(std::uint32_t id, const std::string& info_xml) {
  std::string c;
  Put<std::uint32_t>(&c, id);
  c += "<?xml version=\"1.0\"?><info>" + info_xml + "</info>";
  Chunk(6, c);
}

void XdfWriter::Close() {
  f_.close();
  if (!f_) throw std::runtime_error(path_ + ": write failed");
}

}  // namespace hapticlab::db::internal
