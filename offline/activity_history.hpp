#pragma once
// The remaining material at every station, kept as what changed since the station before: the
// removal is swept once (rank 0), and every worker and rank replays it. A station changes the few
// elements its cut touched, so the history is a small fraction of one full vector per station
// (docs/distributed.md gives the sizes), and it travels to the other ranks in one message.
#include "fem/elastic_problem.hpp"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace drom::offline {

class ActivityHistory {
 public:
  explicit ActivityHistory(std::size_t elements = 0) : elements_(elements) {}

  // The next station's remaining fractions (one per element).
  void append(const std::vector<double>& remaining);
  std::size_t stations() const { return offsets_.size() - 1; }
  std::size_t elements() const { return elements_; }
  // Station k's fractions, from the intact stock.
  std::vector<double> at(std::size_t k) const;
  // Station k - 1's fractions moved on to station k's (k = 0: from the intact stock).
  void advance(std::size_t k, std::vector<double>& fractions) const;
  // What a run of stations first .. last - 1 changes after its first: per element, the first and the
  // last of stations first + 1 .. last - 1 that change it, counted from `first`, or 0 if none does.
  // A change between two fractions below `floor` is none (the FE counts both as removed:
  // fem::ElasticProblem::kMinVolumeFraction).
  fem::RunChanges run_changes(std::size_t first, std::size_t last, double floor) const;
  // Element changes stored over all stations.
  std::size_t changes() const { return changed_.size(); }

  std::string bytes() const;
  // Throws InputError if the bytes are not a history (named `what`).
  static ActivityHistory from_bytes(const std::string& bytes, const std::string& what);

 private:
  std::size_t elements_;
  std::vector<std::uint64_t> offsets_{0};  // station k's changes are [offsets_[k], offsets_[k + 1])
  std::vector<std::int32_t> changed_;      // element
  std::vector<double> value_;              // its new fraction
  std::vector<double> last_;               // the last appended station's fractions (while appending)
};

}  // namespace drom::offline
