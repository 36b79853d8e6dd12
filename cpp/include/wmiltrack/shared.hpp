// An integral image that several threads may share: one thread (or several) recomputes it
// while others read it.
//
// Readers take a snapshot(): a shared pointer to an immutable IntegralImage that stays valid
// (and unchanged) for as long as they hold it, whatever writers do meanwhile. compute() and
// compute_channels() build the new table in an object no reader holds (an earlier table that
// every reader has let go of, else a new one), without any lock held, and then swap the
// pointer under a short lock.
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

  void compute(const ImageView& image, Rect roi) { compute_channels(image, roi, {kLuma}); }
  void compute_channels(const ImageView& image, Rect roi, const std::vector<int>& channels) {
    std::shared_ptr<IntegralImage> next = take_spare();
    next->rebuild(image, roi, channels);  // a throw drops `next`: the snapshot stays
    publish(std::move(next));
  }

  // The current table, or nullptr before the first successful compute.
  std::shared_ptr<const IntegralImage> snapshot() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return current_;
  }

 private:
  // Tables whose last holder has let go come back here (one is kept) to be rebuilt into: a
  // frame the size of the last one then needs no allocation, clearing or page faults. The
  // return happens in the deleter of the table's shared_ptr, after its last reader is done
  // with it, and under the spare's own lock; a table that outlives this object is deleted.
  struct Spare {
    std::mutex mutex;
    std::unique_ptr<IntegralImage> table;
  };
  struct Recycle {
    std::weak_ptr<Spare> spare;
    void operator()(IntegralImage* table) const {
      if (const auto s = spare.lock()) {
        std::lock_guard<std::mutex> lock(s->mutex);
        if (!s->table) {
          s->table.reset(table);
          return;
        }
      }
      delete table;
    }
  };

  std::shared_ptr<IntegralImage> take_spare() {
    std::unique_ptr<IntegralImage> table;
    {
      std::lock_guard<std::mutex> lock(spare_->mutex);
      table.swap(spare_->table);
    }
    if (!table) table = std::make_unique<IntegralImage>();
    return std::shared_ptr<IntegralImage>(table.release(), Recycle{spare_});
  }

  void publish(std::shared_ptr<IntegralImage> next) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      current_.swap(next);
    }
    // `next` now holds the previous table: let go of here, outside the lock (it returns to
    // the spare once its readers are done too).
  }

  mutable std::mutex mutex_;
  std::shared_ptr<IntegralImage> current_;  // handed out as const
  std::shared_ptr<Spare> spare_ = std::make_shared<Spare>();
};

}  // namespace wmiltrack
