// An integral image that several threads may share: one thread (or several) recomputes it
// while others read it.
//
// Readers take a snapshot(): a shared pointer to an immutable IntegralImage that stays valid
// (and unchanged) for as long as they hold it, whatever writers do meanwhile. compute() and
// compute_channels() build the new table in a new object, without any lock held, and then
// swap the pointer under a short lock; the old table is freed when its last reader lets go.
// A failed compute (bad argument, std::bad_alloc) leaves the current snapshot in place.
#pragma once

#include <memory>
#include <mutex>
#include <vector>

#include "wmiltrack/integral.hpp"

namespace wmiltrack {

class SharedIntegralImage {
 public:
  SharedIntegralImage() = default;
  SharedIntegralImage(const SharedIntegralImage&) = delete;
  SharedIntegralImage& operator=(const SharedIntegralImage&) = delete;

  void compute(const ImageView& image, Rect roi) {
    auto next = std::make_shared<IntegralImage>();
    next->compute(image, roi);
    publish(std::move(next));
  }

  void compute_channels(const ImageView& image, Rect roi, const std::vector<int>& channels) {
    auto next = std::make_shared<IntegralImage>();
    next->compute_channels(image, roi, channels);
    publish(std::move(next));
  }

  // The current table, or nullptr before the first successful compute.
  std::shared_ptr<const IntegralImage> snapshot() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return current_;
  }

 private:
  void publish(std::shared_ptr<const IntegralImage> next) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      current_.swap(next);
    }
    // `next` now holds the previous table: released here, outside the lock.
  }

  mutable std::mutex mutex_;
  std::shared_ptr<const IntegralImage> current_;
};

}  // namespace wmiltrack
