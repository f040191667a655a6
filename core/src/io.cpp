#include "hapticlab/core/io.hpp"

#include <fstream>
#include <sstream>

#include "hapticlab/core/diagnostics.hpp"

namespace hapticlab {

std::string ReadTextFile(const std::string& path, const std::string& what) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw InputError(path, 0, "", "cannot open " + what);
  std::ostringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

}  // namespace hapticlab
