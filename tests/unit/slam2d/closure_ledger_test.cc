#include "slam2d/closure_ledger.h"

#include <gtest/gtest.h>

#include <set>

namespace rmap::slam2d {
namespace {

KeyframeClosure closure(size_t query, size_t match) { return {query, match, 0.7, {1.0, 0.0, 0.0}}; }

std::function<bool(size_t)> enabledExcept(std::set<size_t> disabled) {
  return [disabled](size_t edge) { return disabled.count(edge) == 0; };
}

TEST(ClosureLedger, AClosureIsAcceptedOnceAnOptimisationKeepsItsEdge) {
  ClosureLedger ledger;
  ledger.await(10, closure(100, 5));
  ledger.await(11, closure(101, 6));
  EXPECT_TRUE(ledger.takeAccepted().empty());  // not before the optimisation
  const ClosureLedger::Settled settled = ledger.settle(enabledExcept({11}));
  EXPECT_EQ(settled.accepted, 1u);
  EXPECT_EQ(settled.withdrawn, 0u);
  const std::vector<KeyframeClosure> accepted = ledger.takeAccepted();
  ASSERT_EQ(accepted.size(), 1u);
  EXPECT_EQ(accepted[0].query, 100u);
  EXPECT_EQ(accepted[0].match, 5u);
  EXPECT_TRUE(ledger.takeAccepted().empty());
  // The one refused at its own optimisation is never reported, nor withdrawn later.
  EXPECT_EQ(ledger.settle(enabledExcept({11})).withdrawn, 0u);
  EXPECT_TRUE(ledger.takeWithdrawn().empty());
}

// Later closures can show an accepted one wrong: the optimisation that
// disables its edge withdraws it, once.
TEST(ClosureLedger, AnAcceptedClosureWhoseEdgeALaterOptimisationDisablesIsWithdrawn) {
  ClosureLedger ledger;
  ledger.await(10, closure(100, 5));
  ledger.settle(enabledExcept({}));
  ASSERT_EQ(ledger.takeAccepted().size(), 1u);
  ledger.await(12, closure(102, 7));
  const ClosureLedger::Settled settled = ledger.settle(enabledExcept({10}));
  EXPECT_EQ(settled.accepted, 1u);
  EXPECT_EQ(settled.withdrawn, 1u);
  const std::vector<KeyframeClosure> withdrawn = ledger.takeWithdrawn();
  ASSERT_EQ(withdrawn.size(), 1u);
  EXPECT_EQ(withdrawn[0].query, 100u);
  EXPECT_DOUBLE_EQ(withdrawn[0].relative.x_m, 1.0);
  EXPECT_EQ(ledger.takeAccepted().size(), 1u);
  EXPECT_EQ(ledger.settle(enabledExcept({10})).withdrawn, 0u);
  EXPECT_TRUE(ledger.takeWithdrawn().empty());
}

// A caller that takes closures rarely (a benchmark, at the end of a run)
// still sees each accepted closure, and its withdrawal after it.
TEST(ClosureLedger, AClosureWithdrawnBeforeItWasTakenIsReportedBothWays) {
  ClosureLedger ledger;
  ledger.await(10, closure(100, 5));
  ledger.settle(enabledExcept({}));
  ledger.settle(enabledExcept({10}));
  EXPECT_EQ(ledger.takeAccepted().size(), 1u);
  EXPECT_EQ(ledger.takeWithdrawn().size(), 1u);
}

}  // namespace
}  // namespace rmap::slam2d
