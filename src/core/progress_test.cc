#include "src/core/progress.h"

#include <gtest/gtest.h>

namespace hairmvs {
namespace {

// Where() names the current item and its stage, for an error raised within them; a new item
// starts without a stage.
TEST(Progress, WhereNamesTheItemAndItsStage) {
  Progress progress("task", 2);
  progress.Start(0, "a.png");
  EXPECT_EQ(progress.Where(), "a.png");
  progress.Stage("cost volume");
  EXPECT_EQ(progress.Where(), "a.png: cost volume");
  progress.Start(1, "b.png");
  EXPECT_EQ(progress.Where(), "b.png");
}

}  // namespace
}  // namespace hairmvs
