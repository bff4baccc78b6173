#pragma once
// Tasks split over threads behind a plain call (ARCHITECTURE.md: a task-parallel split that the
// caller does not see): the first task on the calling thread, each other one on a thread of its
// own, all joined before the call returns. Plain threads rather than cv::parallel_for_: a TBB
// caller that finishes first spins until the others are done (measured in
// FrameMatcher::compute_two_views: its CPU time did not fall), and the spin takes the core from
// whatever else runs. Used by the feature extraction, the band descriptors and the two-view
// matching of several key images.
#include <cstddef>
#include <exception>
#include <system_error>
#include <thread>
#include <vector>

namespace pepper::core::features {

/// Calls task(i) for i in [0, count): task(0) on the calling thread, the others each on a thread
/// started here (on the calling thread, after task(0)'s start, if a thread cannot be started),
/// and returns once all are done; then rethrows the first exception in task order, if any. The
/// tasks must not share state they write.
template <typename Task>
void run_concurrently(size_t count, Task&& task) {
  std::vector<std::exception_ptr> errors(count);
  auto guarded = [&](size_t i) noexcept {
    try {
      task(i);
    } catch (...) {
      errors[i] = std::current_exception();
    }
  };
  std::vector<std::thread> helpers;
  helpers.reserve(count > 1 ? count - 1 : 0);
  for (size_t i = 1; i < count; ++i) {
    try {
      helpers.emplace_back(guarded, i);
    } catch (const std::system_error&) {
      guarded(i);  // no thread to be had: the work still gets done
    }
  }
  if (count > 0) guarded(0);
  for (std::thread& h : helpers) h.join();
  for (const std::exception_ptr& e : errors) {
    if (e) std::rethrow_exception(e);
  }
}

}  // namespace pepper::core::features
