#include "io/atomic_file.h"

#include <unistd.h>

#include <fstream>
#include <string>

#include "splat/error.h"

namespace app {

void write_atomically(const std::filesystem::path& path,
                      const std::function<void(const std::filesystem::path& tmp)>& write) {
  std::filesystem::path tmp = path;
  // Keep the extension last: some writers (OpenEXR, libpng users) look at it.
  std::string name = ".";
  name.append(path.stem().string()).append(".tmp").append(std::to_string(::getpid()));
  name.append(path.extension().string());
  tmp.replace_filename(name);
  try {
    write(tmp);
    std::filesystem::rename(tmp, path);
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    throw;
  }
}

void write_json(const std::filesystem::path& path, const nlohmann::json& j) {
  write_atomically(path, [&](const std::filesystem::path& tmp) {
    std::ofstream out(tmp);
    out << j.dump(2) << "\n";
    if (!out.flush()) throw splat::Error(tmp.string() + ": write failed");
  });
}

}  // namespace app
