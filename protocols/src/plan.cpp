#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <set>
#include <unordered_map>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/rng.hpp"
#include "hapticlab/protocols/protocol.hpp"

namespace hapticlab::protocols {
namespace {

struct Item {
  PlannedTrial trial;
  std::string key;  // what may not repeat on consecutive trials (the material)
};

// A Fenwick tree of 0/1 counts: prefix sums and the k-th set position in O(log n).
class Fenwick {
 public:
  explicit Fenwick(std::size_t n) : t_(n + 1, 0) {
    for (std::size_t i = 1; i <= n; ++i) {  // all ones, built in O(n)
      t_[i] += 1;
      if (const std::size_t j = i + (i & (~i + 1)); j <= n) t_[j] += t_[i];
    }
  }
  void Remove(std::size_t pos) {
    for (std::size_t i = pos + 1; i < t_.size(); i += i & (~i + 1)) --t_[i];
  }
  std::size_t Prefix(std::size_t end) const {  // ones in [0, end)
    std::size_t s = 0;
    for (std::size_t i = end; i > 0; i -= i & (~i + 1)) s += t_[i];
    return s;
  }
  std::size_t Kth(std::size_t k) const {  // position of the (k+1)-th one
    std::size_t pos = 0, step = 1;
    while (step * 2 < t_.size()) step *= 2;
    for (; step > 0; step /= 2)
      if (pos + step < t_.size() && t_[pos + step] <= k) k -= t_[pos += step];
    return pos;
  }

 private:
  std::vector<std::size_t> t_;
};

// The items NoRepeatOrder has still to place: which are left (in their original order, and per
// key in the key's order) and how many of each key.
struct Remaining {
  std::map<std::string, std::size_t> key_ids;
  std::vector<std::string> keys;
  std::vector<std::size_t> key_of, rank;
  std::vector<std::vector<std::size_t>> positions;  // per key, ascending
  Fenwick all;
  std::vector<Fenwick> per_key;
  std::vector<std::size_t> count;
  std::set<std::pair<std::size_t, std::size_t>> by_count;  // (remaining, key)

  explicit Remaining(const std::vector<Item>& items) : all(items.size()) {
    const std::size_t n = items.size();
    for (const auto& it : items) key_ids.emplace(it.key, 0);
    for (auto& [k, id] : key_ids) id = keys.size(), keys.push_back(k);
    key_of.resize(n);
    rank.resize(n);
    positions.resize(keys.size());
    for (std::size_t i = 0; i < n; ++i) {
      key_of[i] = key_ids[items[i].key];
      rank[i] = positions[key_of[i]].size();
      positions[key_of[i]].push_back(i);
    }
    count.resize(keys.size());
    for (std::size_t k = 0; k < keys.size(); ++k) {
      per_key.emplace_back(positions[k].size());
      count[k] = positions[k].size();
      by_count.emplace(count[k], k);
    }
  }
  std::ptrdiff_t IdOf(const std::string& key) const {
    const auto f = key_ids.find(key);
    return f == key_ids.end() ? -1 : static_cast<std::ptrdiff_t>(f->second);
  }
  // The position of the (j+1)-th remaining item whose key is not `last` (-1: none excluded).
  std::size_t NthAllowed(std::size_t j, std::ptrdiff_t last) const {
    // The smallest position whose prefix holds j + 1 remaining items of another key.
    auto allowed_before = [&](std::size_t end) {
      std::size_t s = all.Prefix(end);
      if (last >= 0) {
        const auto& lp = positions[static_cast<std::size_t>(last)];
        s -= per_key[static_cast<std::size_t>(last)].Prefix(
            static_cast<std::size_t>(std::lower_bound(lp.begin(), lp.end(), end) - lp.begin()));
      }
      return s;
    };
    std::size_t lo = 0, hi = key_of.size() - 1;
    while (lo < hi) {
      const std::size_t mid = lo + (hi - lo) / 2;
      if (allowed_before(mid + 1) >= j + 1)
        hi = mid;
      else
        lo = mid + 1;
    }
    return lo;
  }
  void Remove(std::size_t pick) {
    const std::size_t k = key_of[pick];
    all.Remove(pick);
    per_key[k].Remove(rank[pick]);
    by_count.erase({count[k], k});
    if (--count[k] > 0) by_count.emplace(count[k], k);
  }
};

// Orders `items` randomly such that no two consecutive items share a key (and the first
// differs from `prev`). Greedy with the majority rule: when a key holds more than half of
// what is left it must go next; this succeeds whenever any valid order exists. Each step picks
// uniformly among the remaining items allowed next, in their original order (the draws of the
// plain quadratic version, so plans stay what they were), in O(log^2 n) with Fenwick trees.
std::vector<Item> NoRepeatOrder(std::vector<Item> items, const std::string& prev, bool constrained,
                                Rng& rng, const Protocol& p, const Phase& ph) {
  if (!constrained) {
    rng.Shuffle(items);
    return items;
  }
  const std::size_t n = items.size();
  Remaining r(items);
  std::ptrdiff_t last = r.IdOf(prev);
  std::vector<Item> out;
  out.reserve(n);
  for (std::size_t rem = n; rem > 0; --rem) {
    // A key with 2c - 1 > rem cannot be placed at all; one with 2c - 1 == rem must go now (at
    // most one key can be either).
    const auto [cmax, kmax] = *r.by_count.rbegin();
    const std::size_t clast = last >= 0 ? r.count[static_cast<std::size_t>(last)] : 0;
    const bool stuck_last = last >= 0 && 2 * clast - 1 == rem;
    if (2 * cmax - 1 > rem || stuck_last) {
      const std::size_t k = stuck_last ? static_cast<std::size_t>(last) : kmax;
      throw InputError(
          p.file, ph.line, "randomization.no_immediate_repeat",
          fmt::format(
              "the {} phase cannot avoid immediate repeats: '{}' fills {} of the {} "
              "remaining trials{}",
              ToString(ph.kind), r.keys[k], r.count[k], rem,
              static_cast<std::ptrdiff_t>(k) == last ? " and also ended the previous block" : ""));
    }
    std::size_t pick = 0;
    if (2 * cmax - 1 == rem) {  // forced: one of kmax's items, in their order
      pick = r.positions[kmax][r.per_key[kmax].Kth(rng.Below(cmax))];
    } else {
      const std::size_t candidates = rem - clast;
      if (candidates == 0)
        throw InputError(
            p.file, ph.line, "randomization.no_immediate_repeat",
            fmt::format("the {} phase cannot avoid immediate repeats", ToString(ph.kind)));
      pick = r.NthAllowed(rng.Below(candidates), last);
    }
    const std::size_t k = r.key_of[pick];
    r.Remove(pick);
    last = static_cast<std::ptrdiff_t>(k);
    out.push_back(std::move(items[pick]));
  }
  return out;
}

// Row `r` of a Williams (balanced Latin square) design for n conditions: every condition
// follows every other equally often across rows (2n rows for odd n).
std::vector<int> WilliamsRow(int n, int r) {
  std::vector<int> first;
  for (int i = 0, lo = 1, hi = n - 1; i < n; ++i)
    first.push_back(i == 0 ? 0 : (i % 2 ? lo++ : hi--));
  const int rows = n % 2 ? 2 * n : n;
  r %= rows;
  std::vector<int> row;
  row.reserve(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) row.push_back((first[static_cast<std::size_t>(i)] + r) % n);
  if (r >= n) std::reverse(row.begin(), row.end());
  return row;
}

// Real on the left in half the rated trials (the rest on the right), in random order.
void BalanceSides(std::vector<Item>& items, bool balance, Rng& rng) {
  std::vector<bool> real_left(items.size());
  for (std::size_t i = 0; i < items.size(); ++i)
    real_left[i] = balance ? i < items.size() / 2 : rng.Below(2) == 0;
  if (balance) {
    // An odd count gets its extra trial on a random side.
    if (items.size() % 2) real_left.back() = rng.Below(2) == 0;
    rng.Shuffle(real_left);
  }
  for (std::size_t i = 0; i < items.size(); ++i) {
    auto& t = items[i].trial;
    if (!real_left[i]) std::swap(t.left, t.right);
  }
}

// The plan's size, counted before anything is built (the counts are bounded when parsed,
// their products are not).
double PlannedTrials(const Protocol& p) {
  double planned = 0;
  const double m = static_cast<double>(p.materials.size());
  for (const auto& ph : p.phases) {
    if (ph.adaptive) continue;
    if (ph.kind == PhaseKind::kTraining)
      planned += m;
    else if (ph.kind == PhaseKind::kReference)
      planned += ph.repetitions *
                 ((ph.same_pairs ? m : 0) + static_cast<double>(ph.explicit_pairs.empty()
                                                                    ? ph.different_pairs
                                                                    : ph.explicit_pairs.size()));
    else
      planned += ph.repetitions * m * static_cast<double>(p.methods.size());
  }
  return planned;
}

// Each virtual sample in turn (ch. V.2.1), on the left square; nothing on the right; shuffled.
std::vector<Item> TrainingItems(const Protocol& p, const Phase& ph, Rng& rng) {
  std::vector<Item> items;
  for (const auto& m : p.materials)
    items.push_back({{.phase = ph.kind,
                      .material = m.id,
                      .method = ph.method,
                      .left = "virtual:" + m.id,
                      .rated = false},
                     m.id});
  rng.Shuffle(items);
  return items;
}

// The reference phase's real-real pairs: same-material pairs, then the explicit pairs or
// `different_pairs` drawn once per study from `study_rng`.
std::vector<std::pair<std::string, std::string>> ReferencePairs(const Protocol& p, const Phase& ph,
                                                                Rng& study_rng) {
  std::vector<std::pair<std::string, std::string>> pairs;
  if (ph.same_pairs)
    for (const auto& m : p.materials) pairs.emplace_back(m.id, m.id);
  if (!ph.explicit_pairs.empty()) {
    pairs.insert(pairs.end(), ph.explicit_pairs.begin(), ph.explicit_pairs.end());
  } else if (ph.different_pairs > 0) {
    // Indices, not names, are shuffled (the same draws): m (m - 1) / 2 pairs for m <=
    // kMaxMaterials.
    std::vector<std::pair<std::uint32_t, std::uint32_t>> all;
    all.reserve(p.materials.size() * (p.materials.size() - 1) / 2);
    for (std::uint32_t i = 0; i < p.materials.size(); ++i)
      for (std::uint32_t j = i + 1; j < p.materials.size(); ++j) all.emplace_back(i, j);
    study_rng.Shuffle(all);
    for (int k = 0; k < ph.different_pairs; ++k) {
      const auto [i, j] = all[static_cast<std::size_t>(k)];
      pairs.emplace_back(p.materials[i].id, p.materials[j].id);
    }
  }
  return pairs;
}

std::vector<Item> ReferenceItems(const Phase& ph,
                                 const std::vector<std::pair<std::string, std::string>>& pairs) {
  std::vector<Item> items;
  for (int rep = 0; rep < ph.repetitions; ++rep)
    for (const auto& [a, b] : pairs)
      items.push_back({{.phase = ph.kind,
                        .material = a,
                        .comparison = b,
                        .repetition = rep,
                        .left = "real:" + a,
                        .right = "real:" + b},
                       a});
  return items;
}

// Every material x method x repetition of a main phase, in that nesting.
std::vector<Item> MainItems(const Protocol& p, const Phase& ph) {
  std::vector<Item> all;
  for (int rep = 0; rep < ph.repetitions; ++rep)
    for (const auto& m : p.materials)
      for (const auto& me : p.methods)
        all.push_back({{.phase = ph.kind,
                        .material = m.id,
                        .comparison = "virtual",
                        .method = me.name,
                        .repetition = rep,
                        .left = "real:" + m.id,
                        .right = "virtual:" + m.id},
                       m.id});
  return all;
}

// Blocks of the block_by factor; block order shuffled (blocked) or a Williams row. `starts`
// gets the positions in the result where a block begins.
std::vector<Item> BlockedOrder(const Protocol& p, const Phase& ph, std::vector<Item> all,
                               const std::string& prev0, int participant_index, Rng& rng,
                               std::vector<std::size_t>& starts) {
  const bool constrained = p.randomization.no_immediate_repeat;
  const bool by_method = p.randomization.block_by == "method";
  std::vector<std::string> blocks;
  if (by_method)
    for (const auto& me : p.methods) blocks.push_back(me.name);
  else
    for (const auto& m : p.materials) blocks.push_back(m.id);
  std::vector<int> order(blocks.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  if (p.randomization.scheme == Scheme::kBlocked)
    rng.Shuffle(order);
  else
    order = WilliamsRow(static_cast<int>(blocks.size()), participant_index);
  std::string prev = prev0;
  // Each block's items in their order, grouped in one pass (names are unique).
  std::unordered_map<std::string, std::size_t> block_of;
  for (std::size_t i = 0; i < blocks.size(); ++i) block_of.emplace(blocks[i], i);
  std::vector<std::vector<Item>> grouped(blocks.size());
  for (auto& it : all)
    grouped[block_of.at(by_method ? it.trial.method : it.trial.material)].push_back(std::move(it));
  std::vector<Item> items;
  for (int b : order) {
    auto& block = grouped[static_cast<std::size_t>(b)];
    auto ordered = NoRepeatOrder(std::move(block), prev, constrained, rng, p, ph);
    if (!ordered.empty()) {
      prev = ordered.back().key;
      starts.push_back(items.size());
    }
    items.insert(items.end(), ordered.begin(), ordered.end());
  }
  return items;
}

// A break before every `every_trials`-th rated trial; in a blocked phase it waits for the
// next block boundary (the count restarts at each break). Without blocks this is a break
// before rated trial every_trials, 2 every_trials, ... as always. Also numbers the plan.
void MarkBreaks(const Protocol& p, std::vector<PlannedTrial>& plan,
                const std::vector<bool>& in_blocks, const std::vector<bool>& block_start) {
  int rated = 0, since_break = 0;
  for (std::size_t i = 0; i < plan.size(); ++i) {
    plan[i].index = static_cast<int>(i);
    if (!plan[i].rated) continue;
    const bool may_break = !in_blocks[i] || block_start[i];
    if (p.break_every_trials > 0 && rated > 0 && since_break >= p.break_every_trials && may_break) {
      plan[i].break_before = true;
      since_break = 0;
    }
    ++rated;
    ++since_break;
  }
}

}  // namespace

std::uint64_t ParticipantSeed(const Protocol& p, int participant_index) {
  return DeriveSeed(p.seed, static_cast<std::uint64_t>(participant_index));
}

std::vector<PlannedTrial> Plan(const Protocol& p, int participant_index) {
  if (participant_index < 0) throw InputError(p.file, 0, "participant", "index must be >= 0");
  if (const double planned = PlannedTrials(p); planned > static_cast<double>(kMaxPlannedTrials))
    throw InputError(p.file, 0, "phase",
                     fmt::format("the phases plan {:.0f} trials per participant, more than the {} "
                                 "allowed (fewer materials, methods, pairs or repetitions)",
                                 planned, kMaxPlannedTrials));
  Rng rng(ParticipantSeed(p, participant_index));
  // Different-material reference pairs are drawn once per study (the same for everyone).
  Rng study_rng(DeriveSeed(p.seed, 0xFFFF'FFFFull));
  std::vector<PlannedTrial> plan;
  // Trials of a blocked phase (blocked, latin-square), and those that start a block: a
  // break there falls between blocks, never inside one.
  std::vector<bool> in_blocks, block_start;
  const bool constrained = p.randomization.no_immediate_repeat;
  for (const auto& ph : p.phases) {
    if (ph.adaptive) continue;  // adaptive trials are chosen at run time from the answers
    if (ph.kind == PhaseKind::kTraining) {
      for (auto& it : TrainingItems(p, ph, rng)) plan.push_back(it.trial);
      continue;
    }
    const std::string prev0 = plan.empty() ? "" : plan.back().material;
    std::vector<Item> items;
    if (ph.kind == PhaseKind::kReference) {
      items = NoRepeatOrder(ReferenceItems(ph, ReferencePairs(p, ph, study_rng)), prev0,
                            constrained, rng, p, ph);
    } else if (p.randomization.scheme == Scheme::kFull) {
      items = NoRepeatOrder(MainItems(p, ph), prev0, constrained, rng, p, ph);
    } else {
      std::vector<std::size_t> starts;
      items = BlockedOrder(p, ph, MainItems(p, ph), prev0, participant_index, rng, starts);
      in_blocks.resize(plan.size(), false);
      block_start.resize(plan.size(), false);
      in_blocks.resize(plan.size() + items.size(), true);
      block_start.resize(plan.size() + items.size(), false);
      for (auto s : starts) block_start[plan.size() + s] = true;
    }
    BalanceSides(items, p.randomization.balance_sides, rng);
    for (auto& it : items) plan.push_back(it.trial);
  }
  in_blocks.resize(plan.size(), false);
  block_start.resize(plan.size(), false);
  MarkBreaks(p, plan, in_blocks, block_start);
  return plan;
}

}  // namespace hapticlab::protocols
