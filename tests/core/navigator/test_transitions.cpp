// The navigator's transition table and the switcher's rules (core/navigator/transitions.hpp):
// complete, every row reachable, and printed in docs/method/navigator.md exactly as the code has
// them (the docs cannot drift from the code).
#include "core/navigator/transitions.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "core/localization/key_image_logic.hpp"

namespace pepper::core::navigator {
namespace {

constexpr NavState kStates[] = {NavState::kNotLocalized, NavState::kNavigating,
                                NavState::kHolding,      NavState::kDeadReckoning,
                                NavState::kLost,         NavState::kTourComplete,
                                NavState::kOverdue};
constexpr unsigned kFactCombinations = 128;  // 2^(fields of StepFacts)
constexpr Phase kPhases[] = {Phase::kEntry, Phase::kLocalise, Phase::kSegment, Phase::kControl};

StepFacts facts_from_bits(unsigned bits) {
  StepFacts f;
  f.localised = bits & 1;
  f.final_reached = bits & 2;
  f.switched = bits & 4;
  f.overdue = bits & 8;
  f.has_demand = bits & 16;
  f.within_hold = bits & 32;
  f.can_dead_reckon = bits & 64;
  return f;
}

// Where a phase has a row for a state, some row decides for every combination of facts.
TEST(NavigatorTransitions, EveryPhaseIsCompleteForItsStates) {
  for (const Phase p : kPhases) {
    for (const NavState s : kStates) {
      if (decide(p, s, StepFacts{}) == nullptr) {
        for (unsigned bits = 0; bits < kFactCombinations; ++bits) {
          EXPECT_EQ(decide(p, s, facts_from_bits(bits)), nullptr)
              << to_string(p) << " " << to_string(s) << ": a row applies only to some facts";
        }
        continue;
      }
      for (unsigned bits = 0; bits < kFactCombinations; ++bits) {
        EXPECT_NE(decide(p, s, facts_from_bits(bits)), nullptr) << to_string(p) << " "
                                                                << to_string(s) << " " << bits;
      }
    }
  }
  // The terminal states are decided on entry; no stage runs in them.
  for (const Phase p : {Phase::kLocalise, Phase::kSegment, Phase::kControl}) {
    EXPECT_EQ(decide(p, NavState::kTourComplete, StepFacts{}), nullptr);
    EXPECT_EQ(decide(p, NavState::kOverdue, StepFacts{}), nullptr);
  }
}

// No row is shadowed by the rows before it.
TEST(NavigatorTransitions, EveryRowDecidesSomewhere) {
  std::set<const Transition*> used;
  for (const Phase p : kPhases) {
    for (const NavState s : kStates) {
      for (unsigned bits = 0; bits < kFactCombinations; ++bits) {
        if (const Transition* t = decide(p, s, facts_from_bits(bits))) used.insert(t);
      }
    }
  }
  for (const Transition& t : transition_table()) {
    EXPECT_TRUE(used.count(&t)) << to_string(t.phase) << " " << t.condition << " never decides";
  }
}

// docs/method/navigator.md prints both tables between markers, as generated here.
TEST(NavigatorTransitions, DocsShowTheTablesOfTheCode) {
  std::ifstream in(std::string(PEPPER_SOURCE_DIR) + "/docs/method/navigator.md");
  ASSERT_TRUE(in);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string doc = ss.str();
  auto block = [&](const std::string& name) {
    const std::string begin = "<!-- " + name + ": generated from the code, see test_transitions.cpp -->\n";
    const std::string end = "<!-- end of " + name + " -->";
    const auto b = doc.find(begin);
    const auto e = doc.find(end);
    if (b == std::string::npos || e == std::string::npos || e < b) return std::string("(missing)");
    return doc.substr(b + begin.size(), e - b - begin.size());
  };
  // PEPPER_REGENERATE_DOCS=1 rewrites the blocks from the code (then review the diff).
  if (const char* regen = std::getenv("PEPPER_REGENERATE_DOCS"); regen && *regen == '1') {
    std::string updated = doc;
    auto replace = [&](const std::string& name, const std::string& body) {
      const std::string begin =
          "<!-- " + name + ": generated from the code, see test_transitions.cpp -->\n";
      const auto b = updated.find(begin);
      const auto e = updated.find("<!-- end of " + name + " -->");
      ASSERT_TRUE(b != std::string::npos && e != std::string::npos && e > b) << name;
      updated.replace(b + begin.size(), e - b - begin.size(), body);
    };
    replace("transition table", transition_table_markdown());
    replace("switch rules", switch_rules_markdown());
    std::ofstream(std::string(PEPPER_SOURCE_DIR) + "/docs/method/navigator.md") << updated;
    return;
  }
  EXPECT_EQ(block("transition table"), transition_table_markdown());
  EXPECT_EQ(block("switch rules"), switch_rules_markdown());
}

// The switcher's table decides as the rules say: a paper rule wants a switch unless the guard
// blocks; an addition wants one regardless.
TEST(NavigatorTransitions, SwitchRulesDecideTheSwitcher) {
  using localization::KeyImageSwitcher;
  using localization::Segment;
  using localization::SwitchCounts;
  localization::SwitcherOptions o;
  o.consecutive_frames = 1;
  SwitchCounts paper;  // two-view rule holds, the scale says "far from IN": blocked
  paper.two_view_next_next = 30;
  paper.two_view_next = 10;
  paper.two_view_prev = 5;
  paper.next_scale_ratio = 0.5;
  KeyImageSwitcher a(localization::segment_ending_at(1, 5), 5, o);
  auto u = a.update(paper, false);
  EXPECT_EQ(u.event, localization::SwitchEvent::kNone);
  EXPECT_EQ(u.criteria_bits, 2 | localization::kCriterionGuardBlocked);
  paper.next_scale_ratio = 0.95;  // near IN: the guard lets it through
  u = a.update(paper, false);
  EXPECT_EQ(u.event, localization::SwitchEvent::kSwitched);
  SwitchCounts passed;  // no paper rule, IN's points larger than taught: no rule by scale alone
  passed.next_scale_ratio = 1.2;
  u = a.update(passed, false);
  EXPECT_EQ(u.event, localization::SwitchEvent::kNone);
  EXPECT_EQ(u.criteria_bits, 0);
  passed.passed_by_odometry = true;  // the odometry past IN: wanted, on two frames
  EXPECT_EQ(a.update(passed, false).criteria_bits, localization::kCriterionPassedByOdometry);
  EXPECT_EQ(a.update(passed, false).event, localization::SwitchEvent::kSwitched);
}

}  // namespace
}  // namespace pepper::core::navigator
