#include <fmt/format.h>

#include <algorithm>
#include <map>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/core/rng.hpp"
#include "hapticlab/protocols/protocol.hpp"

namespace hapticlab::protocols {
namespace {

struct Item {
  PlannedTrial trial;
  std::string key;  // what may not repeat on consecutive trials (the material)
};

// Orders `items` randomly such that no two consecutive items share a key (and the first
// differs from `prev`). Greedy with the majority rule: when a key holds more than half of
// what is left it must go next; this succeeds whenever any valid order exists.
std::vector<Item> NoRepeatOrder(std::vector<Item> items, const std::string& prev, bool constrained,
                                Rng& rng, const Protocol& p, const Phase& ph) {
  if (!constrained) {
    rng.Shuffle(items);
    return items;
  }
  std::vector<Item> out;
  std::string last = prev;
  while (!items.empty()) {
    std::map<std::string, int> count;
    for (const auto& it : items) ++count[it.key];
    const int rem = static_cast<int>(items.size());
    // A key with c > ceil(rem / 2) cannot be placed at all; one with 2c - 1 == rem must go now.
    for (const auto& [k, c] : count) {
      if (2 * c - 1 > rem || (2 * c - 1 == rem && k == last))
        throw InputError(
            p.file, ph.line, "randomization.no_immediate_repeat",
            fmt::format(
                "the {} phase cannot avoid immediate repeats: '{}' fills {} of the {} remaining "
                "trials{}",
                ToString(ph.kind), k, c, rem,
                k == last ? " and also ended the previous block" : ""));
    }
    std::string forced;
    for (const auto& [k, c] : count)
      if (2 * c - 1 == rem) forced = k;
    std::vector<std::size_t> candidates;
    for (std::size_t i = 0; i < items.size(); ++i)
      if (items[i].key != last && (forced.empty() || items[i].key == forced))
        candidates.push_back(i);
    if (candidates.empty())
      throw InputError(
          p.file, ph.line, "randomization.no_immediate_repeat",
          fmt::format("the {} phase cannot avoid immediate repeats", ToString(ph.kind)));
    const std::size_t pick = candidates[rng.Below(candidates.size())];
    last = items[pick].key;
    out.push_back(std::move(items[pick]));
    items.erase(items.begin() + static_cast<std::ptrdiff_t>(pick));
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

}  // namespace

std::uint64_t ParticipantSeed(const Protocol& p, int participant_index) {
  return DeriveSeed(p.seed, static_cast<std::uint64_t>(participant_index));
}

std::vector<PlannedTrial> Plan(const Protocol& p, int participant_index) {
  if (participant_index < 0) throw InputError(p.file, 0, "participant", "index must be >= 0");
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
    std::vector<Item> items;
    if (ph.kind == PhaseKind::kTraining) {
      for (const auto& m : p.materials)
        // Each virtual sample in turn (ch. V.2.1), on the left square; nothing on the right.
        items.push_back({{.phase = ph.kind,
                          .material = m.id,
                          .method = ph.method,
                          .left = "virtual:" + m.id,
                          .rated = false},
                         m.id});
      rng.Shuffle(items);
      for (auto& it : items) plan.push_back(it.trial);
      continue;
    }
    if (ph.kind == PhaseKind::kReference) {
      std::vector<std::pair<std::string, std::string>> pairs;
      if (ph.same_pairs)
        for (const auto& m : p.materials) pairs.emplace_back(m.id, m.id);
      if (!ph.explicit_pairs.empty()) {
        pairs.insert(pairs.end(), ph.explicit_pairs.begin(), ph.explicit_pairs.end());
      } else if (ph.different_pairs > 0) {
        std::vector<std::pair<std::string, std::string>> all;
        for (std::size_t i = 0; i < p.materials.size(); ++i)
          for (std::size_t j = i + 1; j < p.materials.size(); ++j)
            all.emplace_back(p.materials[i].id, p.materials[j].id);
        study_rng.Shuffle(all);
        pairs.insert(pairs.end(), all.begin(), all.begin() + ph.different_pairs);
      }
      for (int rep = 0; rep < ph.repetitions; ++rep)
        for (const auto& [a, b] : pairs)
          items.push_back({{.phase = ph.kind,
                            .material = a,
                            .comparison = b,
                            .repetition = rep,
                            .left = "real:" + a,
                            .right = "real:" + b},
                           a});
      items = NoRepeatOrder(std::move(items), plan.empty() ? "" : plan.back().material, constrained,
                            rng, p, ph);
    } else {
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
      const std::string prev0 = plan.empty() ? "" : plan.back().material;
      if (p.randomization.scheme == Scheme::kFull) {
        items = NoRepeatOrder(std::move(all), prev0, constrained, rng, p, ph);
      } else {
        // Blocks of the block_by factor; block order shuffled (blocked) or a Williams row.
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
        std::vector<std::size_t> starts;  // positions in `items` where a block begins
        for (int b : order) {
          std::vector<Item> block;
          for (const auto& it : all)
            if ((by_method ? it.trial.method : it.trial.material) ==
                blocks[static_cast<std::size_t>(b)])
              block.push_back(it);
          auto ordered = NoRepeatOrder(std::move(block), prev, constrained, rng, p, ph);
          if (!ordered.empty()) {
            prev = ordered.back().key;
            starts.push_back(items.size());
          }
          items.insert(items.end(), ordered.begin(), ordered.end());
        }
        in_blocks.resize(plan.size(), false);
        block_start.resize(plan.size(), false);
        in_blocks.resize(plan.size() + items.size(), true);
        block_start.resize(plan.size() + items.size(), false);
        for (auto s : starts) block_start[plan.size() + s] = true;
      }
    }
    BalanceSides(items, p.randomization.balance_sides, rng);
    for (auto& it : items) plan.push_back(it.trial);
  }
  in_blocks.resize(plan.size(), false);
  block_start.resize(plan.size(), false);
  // A break before every `every_trials`-th rated trial; in a blocked phase it waits for the
  // next block boundary (the count restarts at each break). Without blocks this is a break
  // before rated trial every_trials, 2 every_trials, ... as always.
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
  return plan;
}

}  // namespace hapticlab::protocols
