#pragma once
// Means over consecutive blocks of simulated time: what a servo phase or a steadiness check
// judges instead of one step's rattling value.

namespace demcal::lab {

/// Means of a quantity (and a second one alongside) over consecutive blocks of simulated time.
class BlockMeans {
 public:
  BlockMeans(double start, double length) : start_(start), length_(length) {}
  /// Adds one step's values at `time`; true when the step closes a block, whose means mean_a()
  /// and mean_b() then hold until the next one closes.
  bool add(double time, double a, double b = 0.0) {
    sum_a_ += a;
    sum_b_ += b;
    ++n_;
    if (time - start_ < length_) return false;
    close(time);
    return true;
  }
  /// Closes the block still open, if it has a step, at `time`: a phase that ends before its block
  /// is complete reports the means of the steps it ran.
  void close(double time) {
    if (n_ == 0) return;
    mean_a_ = sum_a_ / static_cast<double>(n_);
    mean_b_ = sum_b_ / static_cast<double>(n_);
    start_ = time;
    sum_a_ = sum_b_ = 0.0;
    n_ = 0;
    ++blocks_;
  }
  double mean_a() const { return mean_a_; }
  double mean_b() const { return mean_b_; }
  int blocks() const { return blocks_; }

 private:
  double start_, length_;
  double sum_a_ = 0.0, sum_b_ = 0.0, mean_a_ = 0.0, mean_b_ = 0.0;
  long n_ = 0;
  int blocks_ = 0;
};

}  // namespace demcal::lab
