// Checks shared by the bake tests (test_visibility.cpp, the randomized test_bake_properties.cpp).
#pragma once

#include "sdlighting/visibility.h"

#include <gtest/gtest.h>

#include <cstddef>

namespace sd::test {

/// Every output of two bakes is bit-identical.
inline void expect_same(const TransferBake& a, const TransferBake& b) {
  EXPECT_EQ(a.ray_origins, b.ray_origins);
  EXPECT_EQ(a.ambient_occlusion, b.ambient_occlusion);
  EXPECT_EQ(a.visibility, b.visibility);
  EXPECT_EQ(a.product_matrices, b.product_matrices);
  EXPECT_EQ(a.transfer, b.transfer);
  EXPECT_EQ(a.design_offsets, b.design_offsets);
  EXPECT_EQ(a.design_weights, b.design_weights);
  ASSERT_EQ(a.design_nodes.size(), b.design_nodes.size());
  for (std::size_t i = 0; i < a.design_nodes.size(); ++i) EXPECT_EQ(a.design_nodes[i], b.design_nodes[i]);
  EXPECT_EQ(a.ray_visibility, b.ray_visibility);
  EXPECT_EQ(a.fallback_normals, b.fallback_normals);
}

}  // namespace sd::test
