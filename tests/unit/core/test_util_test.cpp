// The shared test helpers themselves.
#include "../test_util.h"

namespace s2c::test {

TEST(TestUtil, IcosphereIsClosedAndOutward) {
  const auto s = icosphere(Eigen::Vector3d::Zero(), 1.0, 2);
  EXPECT_EQ(s.faces.size(), 320u);
  double vol = 0;
  for (const auto& f : s.faces) vol += s.vertices[f[0]].dot(s.vertices[f[1]].cross(s.vertices[f[2]])) / 6;
  EXPECT_GT(vol, 4.0);  // 4/3 π ≈ 4.19
}

}  // namespace s2c::test
