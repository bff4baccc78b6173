#pragma once
// Where the real-image benchmarks find Pepper's images: shared/data/pepper_qut_tmap beside the
// checkout (PEPPER_SHARED_DIR, set by bench/CMakeLists.txt), or the folder named by the
// PEPPER_QUT_TMAP_DIR environment variable.
#include <benchmark/benchmark.h>
#include <opencv2/core/utility.hpp>

#include <cstdlib>
#include <exception>
#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <string>

namespace pepper::bench {

inline std::filesystem::path real_data_dir() {
  if (const char* env = std::getenv("PEPPER_QUT_TMAP_DIR"); env != nullptr && *env != '\0')
    return env;
  return std::filesystem::path(PEPPER_SHARED_DIR) / "data" / "pepper_qut_tmap";
}

/// The main of a real-image benchmark: OpenCV on one thread, then `load` (read the images, build
/// the maps) before any benchmark runs, so that missing data fails the program with exit 2 and
/// a message naming the folder instead of being reported as skipped benchmarks.
template <class Load>
int run_real_benchmarks(int argc, char** argv, const char* name, Load load) {
  cv::setNumThreads(1);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  try {
    if (!std::filesystem::is_directory(real_data_dir()))
      throw std::runtime_error("real Pepper data folder " + real_data_dir().string() +
                               " not found (shared/data/pepper_qut_tmap; set "
                               "PEPPER_QUT_TMAP_DIR to its folder)");
    load();
  } catch (const std::exception& e) {
    std::cerr << name << ": " << e.what() << "\n";
    return 2;
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

}  // namespace pepper::bench
