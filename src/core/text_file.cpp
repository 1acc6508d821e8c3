// SPDX-License-Identifier: MIT
#include "core/text_file.hpp"

#include <filesystem>
#include <fstream>

#include "core/errors.hpp"

namespace tessera {

void write_file_atomically(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    out << text;
    out.flush();
    if (!out) throw RunError("cannot write " + tmp);
  }
  std::filesystem::rename(tmp, path);
}

}  // namespace tessera
