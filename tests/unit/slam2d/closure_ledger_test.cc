#include "slam2d/closure_ledger.h"

#include <gtest/gtest.h>

#include <set>
#include <stdexcept>

namespace rmap::slam2d {
namespace {

KeyframeClosure closure(size_t query, size_t match) { return {query, match, 0.7, {1.0, 0.0, 0.0}, {}}; }

std::function<bool(size_t)> enabledExcept(std::set<size_t> disabled) {
  return [disabled](size_t edge) { return disabled.count(edge) == 0; };
}

/// Every trajectory's sensor time is `now_ns`.
std::function<int64_t(size_t)> at(int64_t now_ns) {
  return [now_ns](size_t) { return now_ns; };
}

constexpr int64_t kSecond = 1'000'000'000;

// Without a hold (hold_ns 0) the optimisation after a closure decides at once.
TEST(ClosureLedger, AClosureIsAcceptedOnceAnOptimisationKeepsItsEdge) {
  ClosureLedger ledger;
  ledger.await(10, closure(100, 5), 0);
  ledger.await(11, closure(101, 6), 0);
  EXPECT_TRUE(ledger.takeAccepted().empty());  // not before the optimisation
  const ClosureLedger::Settled settled = ledger.settle(enabledExcept({11}), at(0));
  EXPECT_EQ(settled.accepted, 1u);
  EXPECT_EQ(settled.withdrawn, 0u);
  const std::vector<KeyframeClosure> accepted = ledger.takeAccepted();
  ASSERT_EQ(accepted.size(), 1u);
  EXPECT_EQ(accepted[0].query, 100u);
  EXPECT_EQ(accepted[0].match, 5u);
  EXPECT_TRUE(ledger.takeAccepted().empty());
  // The one refused at its own optimisation is never reported, nor withdrawn later.
  EXPECT_EQ(ledger.settle(enabledExcept({11}), at(0)).withdrawn, 0u);
  EXPECT_TRUE(ledger.takeWithdrawn().empty());
}

// Later closures can show an accepted one wrong: the optimisation that
// disables its edge withdraws it, once.
TEST(ClosureLedger, AnAcceptedClosureWhoseEdgeALaterOptimisationDisablesIsWithdrawn) {
  ClosureLedger ledger;
  ledger.await(10, closure(100, 5), 0);
  ledger.settle(enabledExcept({}), at(0));
  ASSERT_EQ(ledger.takeAccepted().size(), 1u);
  ledger.await(12, closure(102, 7), 0);
  const ClosureLedger::Settled settled = ledger.settle(enabledExcept({10}), at(0));
  EXPECT_EQ(settled.accepted, 1u);
  EXPECT_EQ(settled.withdrawn, 1u);
  const std::vector<KeyframeClosure> withdrawn = ledger.takeWithdrawn();
  ASSERT_EQ(withdrawn.size(), 1u);
  EXPECT_EQ(withdrawn[0].query, 100u);
  EXPECT_DOUBLE_EQ(withdrawn[0].relative.x_m, 1.0);
  EXPECT_EQ(ledger.takeAccepted().size(), 1u);
  EXPECT_EQ(ledger.settle(enabledExcept({10}), at(0)).withdrawn, 0u);
  EXPECT_TRUE(ledger.takeWithdrawn().empty());
}

// A caller that takes closures rarely (a benchmark, at the end of a run)
// still sees each accepted closure, and its withdrawal after it.
// The accepted report carries the matched submap; the ledger does not keep it.
TEST(ClosureLedger, AClosureWithdrawnBeforeItWasTakenIsReportedBothWays) {
  ClosureLedger ledger;
  KeyframeClosure c = closure(100, 5);
  c.submap = {{4, {-0.5, 0.0, 0.0}}, {5, {}}, {6, {0.5, 0.0, 0.0}}};
  ledger.await(10, c, 0);
  ledger.settle(enabledExcept({}), at(0));
  ledger.settle(enabledExcept({10}), at(0));
  const std::vector<KeyframeClosure> accepted = ledger.takeAccepted(), withdrawn = ledger.takeWithdrawn();
  ASSERT_EQ(accepted.size(), 1u);
  ASSERT_EQ(withdrawn.size(), 1u);
  EXPECT_EQ(accepted[0].submap.size(), 3u);
  EXPECT_EQ(withdrawn[0].query, 100u);
  EXPECT_TRUE(withdrawn[0].submap.empty());
}

// With a hold, a closure kept alone is only tentative: the closures found after
// it may show it wrong at the next optimisation, before anyone was told.
TEST(ClosureLedger, ATentativeClosureALaterOptimisationDisablesIsNeverReported) {
  ClosureLedger ledger(5 * kSecond);
  ledger.await(10, closure(100, 5), 0);
  EXPECT_EQ(ledger.settle(enabledExcept({}), at(0)).accepted, 0u);
  EXPECT_TRUE(ledger.takeAccepted().empty());
  ledger.await(11, closure(101, 6), 0);
  const ClosureLedger::Settled settled = ledger.settle(enabledExcept({10}), at(kSecond));
  EXPECT_EQ(settled.dropped_tentative, 1u);
  EXPECT_EQ(settled.withdrawn, 0u);
  EXPECT_EQ(settled.accepted, 0u);  // 11 is tentative in turn
  EXPECT_TRUE(ledger.takeAccepted().empty());
  EXPECT_TRUE(ledger.takeWithdrawn().empty());
  // Past the hold the one the graph kept is accepted; the dropped one never comes back.
  EXPECT_EQ(ledger.confirmHeld(0, 6 * kSecond), 1u);
  const std::vector<KeyframeClosure> accepted = ledger.takeAccepted();
  ASSERT_EQ(accepted.size(), 1u);
  EXPECT_EQ(accepted[0].query, 101u);
}

TEST(ClosureLedger, ATentativeClosureALaterOptimisationKeepsIsAccepted) {
  ClosureLedger ledger(5 * kSecond);
  ledger.await(10, closure(100, 5), 0);
  ledger.settle(enabledExcept({}), at(0));
  ledger.await(11, closure(101, 6), 0);
  const ClosureLedger::Settled settled = ledger.settle(enabledExcept({}), at(kSecond));
  EXPECT_EQ(settled.accepted, 1u);
  const std::vector<KeyframeClosure> accepted = ledger.takeAccepted();
  ASSERT_EQ(accepted.size(), 1u);
  EXPECT_EQ(accepted[0].query, 100u);
  // Accepted now, so a later disable withdraws it.
  EXPECT_EQ(ledger.settle(enabledExcept({10}), at(2 * kSecond)).withdrawn, 1u);
}

// A trajectory's hold runs on its own sensor time: robots' clocks differ.
TEST(ClosureLedger, AHeldClosureIsAcceptedAfterTheHoldOfItsOwnTrajectory) {
  ClosureLedger ledger(5 * kSecond);
  ledger.await(10, closure(100, 5), 1);
  ledger.settle(enabledExcept({}), [](size_t t) { return t == 1 ? 100 * kSecond : 0; });
  EXPECT_EQ(ledger.confirmHeld(0, 1000 * kSecond), 0u);  // another robot's clock
  EXPECT_EQ(ledger.confirmHeld(1, 104 * kSecond), 0u);   // not held long enough
  EXPECT_TRUE(ledger.takeAccepted().empty());
  EXPECT_EQ(ledger.confirmHeld(1, 105 * kSecond), 1u);
  EXPECT_EQ(ledger.takeAccepted().size(), 1u);
  EXPECT_EQ(ledger.confirmHeld(1, 200 * kSecond), 0u);  // once
}

// At the end of the data the tentative closures count; the ones no
// optimisation has seen yet do not.
TEST(ClosureLedger, ConfirmAllAcceptsTheTentativeOnesOnly) {
  ClosureLedger ledger(5 * kSecond);
  ledger.await(10, closure(100, 5), 0);
  ledger.settle(enabledExcept({}), at(0));
  ledger.await(11, closure(101, 6), 0);
  EXPECT_EQ(ledger.confirmAll(), 1u);
  const std::vector<KeyframeClosure> accepted = ledger.takeAccepted();
  ASSERT_EQ(accepted.size(), 1u);
  EXPECT_EQ(accepted[0].query, 100u);
  EXPECT_EQ(ledger.settle(enabledExcept({}), at(0)).accepted, 0u);  // 11 now tentative
}

TEST(ClosureLedger, ANegativeHoldIsRefused) { EXPECT_THROW(ClosureLedger(-1), std::invalid_argument); }

}  // namespace
}  // namespace rmap::slam2d
