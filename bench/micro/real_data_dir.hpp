#pragma once
// Where the real-image benchmarks find Pepper's images: shared/data/pepper_qut_tmap beside the
// checkout (PEPPER_SHARED_DIR, set by bench/CMakeLists.txt), or the folder named by the
// PEPPER_QUT_TMAP_DIR environment variable.
#include <cstdlib>
#include <filesystem>

namespace pepper::bench {

inline std::filesystem::path real_data_dir() {
  if (const char* env = std::getenv("PEPPER_QUT_TMAP_DIR"); env != nullptr && *env != '\0')
    return env;
  return std::filesystem::path(PEPPER_SHARED_DIR) / "data" / "pepper_qut_tmap";
}

}  // namespace pepper::bench
