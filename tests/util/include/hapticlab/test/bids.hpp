#pragma once
// Independent readers for the BIDS export tests (db and apps): zlib for the .tsv.gz
// recordings, and the official bids-validator (npm, pinned; installed by scripts/setup into
// tools/bids-validator). Header-only: the including test links zlib and nlohmann-json.

#include <zlib.h>

#include <nlohmann/json.hpp>
#include <string>

#include "hapticlab/test/test_util.hpp"

namespace hapticlab::test {

/// The validator's executable (present after scripts/setup).
inline std::string BidsValidator() {
  return std::string(HL_SOURCE_DIR) + "/tools/bids-validator/node_modules/.bin/bids-validator";
}

/// A gzip file's contents; "" when it cannot be opened.
inline std::string Gunzip(const std::string& path) {
  gzFile f = gzopen(path.c_str(), "rb");
  if (!f) return "";
  std::string s;
  char buf[65536];
  int n;
  while ((n = gzread(f, buf, sizeof buf)) > 0) s.append(buf, static_cast<std::size_t>(n));
  gzclose(f);
  return s;
}

/// Runs the validator on a dataset; its JSON report (stdout) goes to a file beside it, its Node
/// warnings aside. Exit status 1 means "errors found": the report says which.
inline nlohmann::json ValidateBids(const std::string& dataset) {
  std::string out;
  const std::string report = dataset + ".validator.json";
  RunCommand("(" + BidsValidator() + " " + dataset + " --json > " + report + ")", &out);
  auto j = nlohmann::json::parse(ReadFile(report), nullptr, false);
  if (j.is_discarded()) return {{"unparsed", ReadFile(report)}, {"stderr", out}};
  return j;
}

}  // namespace hapticlab::test
