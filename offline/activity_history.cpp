#include "offline/activity_history.hpp"

#include "support/byte_stream.hpp"
#include "support/input_error.hpp"

#include <cmath>
#include <stdexcept>

namespace drom::offline {

void ActivityHistory::append(const std::vector<double>& remaining) {
  if (remaining.size() != elements_) throw std::invalid_argument("ActivityHistory: one fraction per element");
  if (last_.empty()) last_ = stations() == 0 ? std::vector<double>(elements_, 1.0) : at(stations() - 1);
  for (std::size_t e = 0; e < elements_; ++e)
    // Bit for bit: a fraction that changes in its last digit is a change.
    if (remaining[e] != last_[e] || std::signbit(remaining[e]) != std::signbit(last_[e])) {
      changed_.push_back(static_cast<std::int32_t>(e));
      value_.push_back(remaining[e]);
      last_[e] = remaining[e];
    }
  offsets_.push_back(changed_.size());
}

void ActivityHistory::advance(std::size_t k, std::vector<double>& fractions) const {
  if (k >= stations()) throw std::out_of_range("ActivityHistory: station " + std::to_string(k) + " of " + std::to_string(stations()));
  if (k == 0) fractions.assign(elements_, 1.0);
  for (auto i = offsets_[k]; i < offsets_[k + 1]; ++i) fractions[static_cast<std::size_t>(changed_[i])] = value_[i];
}

fem::RunChanges ActivityHistory::run_changes(std::size_t first, std::size_t last, double floor) const {
  if (first >= last || last > stations()) throw std::out_of_range("ActivityHistory: stations " + std::to_string(first) + " to " + std::to_string(last));
  std::vector<double> fractions = at(first);
  fem::RunChanges changes{std::vector<int>(elements_, 0), std::vector<int>(elements_, 0), static_cast<int>(last - first)};
  for (std::size_t k = first + 1; k < last; ++k)
    for (auto i = offsets_[k]; i < offsets_[k + 1]; ++i) {
      const auto e = static_cast<std::size_t>(changed_[i]);
      const double before = fractions[e];
      fractions[e] = value_[i];
      if (before < floor && value_[i] < floor) continue;
      const int station = static_cast<int>(k - first);
      if (changes.first[e] == 0) changes.first[e] = station;
      changes.last[e] = station;
    }
  return changes;
}

std::vector<double> ActivityHistory::at(std::size_t k) const {
  std::vector<double> fractions;
  for (std::size_t j = 0; j <= k; ++j) advance(j, fractions);
  return fractions;
}

std::string ActivityHistory::bytes() const {
  ByteWriter w;
  w.put<std::uint64_t>(elements_);
  w.put(offsets_);
  w.put(changed_);
  w.put(value_);
  return w.take();
}

ActivityHistory ActivityHistory::from_bytes(const std::string& bytes, const std::string& what) {
  ByteReader r(bytes, what);
  ActivityHistory h(r.get<std::uint64_t>());
  h.offsets_ = r.vector<std::uint64_t>();
  h.changed_ = r.vector<std::int32_t>();
  h.value_ = r.vector<double>();
  bool valid = !h.offsets_.empty() && h.offsets_.front() == 0 && h.offsets_.back() == h.changed_.size() && h.changed_.size() == h.value_.size();
  for (std::size_t k = 0; valid && k + 1 < h.offsets_.size(); ++k) valid = h.offsets_[k] <= h.offsets_[k + 1];
  for (std::int32_t e : h.changed_) valid = valid && e >= 0 && static_cast<std::size_t>(e) < h.elements_;
  if (!valid || !r.done()) throw InputError(what + ": not a station activity history");
  return h;
}

}  // namespace drom::offline
