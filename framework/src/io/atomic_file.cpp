// Atomic file output (rsvio/io/atomic_file.h): temporary file in the same folder, then rename(2).
#include "rsvio/io/atomic_file.h"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "rsvio/core/error.h"

namespace rsvio::io {

std::string atomicTempPath(const std::string& path) { return path + ".tmp-" + std::to_string(::getpid()); }

void writeFileAtomic(const std::string& path, const std::function<void(std::ostream&)>& fill, const std::string& what,
                     bool binary) {
  const std::string tmp = atomicTempPath(path);
  {
    std::ofstream out(tmp, binary ? std::ios::binary | std::ios::trunc : std::ios::trunc);
    if (!out) throw Error(path + ": cannot write " + what + " (" + std::strerror(errno) + ")");
    try {
      fill(out);
      out.flush();
    } catch (...) {
      out.close();
      std::remove(tmp.c_str());
      throw;
    }
    if (!out) {
      out.close();
      std::remove(tmp.c_str());
      throw Error(path + ": write failed (" + what + ")");
    }
    out.close();
    if (!out) {
      std::remove(tmp.c_str());
      throw Error(path + ": write failed (" + what + ")");
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    std::remove(tmp.c_str());
    throw Error(path + ": cannot write " + what + " (rename: " + why + ")");
  }
}

}  // namespace rsvio::io
