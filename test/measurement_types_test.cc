#include "rff_ceres/measurement_types.h"

#include <memory>
#include <set>
#include <string>
#include <vector>

#include "gtest/gtest.h"
#include "rff_ceres/slam_problem.h"

namespace rff {
namespace {

TEST(MeasurementTypesTest, TableIsInObservationTypeOrderWithUniqueNames) {
  const std::vector<MeasurementType>& types = MeasurementTypes();
  ASSERT_EQ(types.size(), 3u);
  std::set<std::string> records, kinds;
  for (std::size_t i = 0; i < types.size(); ++i) {
    EXPECT_EQ(static_cast<std::size_t>(types[i].type), i);
    EXPECT_TRUE(types[i].range || types[i].bearing) << types[i].record;
    records.insert(types[i].record);
    kinds.insert(types[i].kind);
  }
  EXPECT_EQ(records,
            (std::set<std::string>{"RANGE", "BEARING", "RANGE_BEARING"}));
  EXPECT_EQ(kinds,
            (std::set<std::string>{"range", "bearing", "range-bearing"}));
}

TEST(MeasurementTypesTest, LookupsByRecordAndKind) {
  EXPECT_EQ(FindMeasurementRecord("BEARING")->type, ObservationType::kBearing);
  EXPECT_EQ(FindMeasurementKind("range-bearing")->type,
            ObservationType::kRangeBearing);
  EXPECT_EQ(FindMeasurementRecord("range"), nullptr);  // Records are upper.
  EXPECT_EQ(FindMeasurementKind("odometry"), nullptr);
  Observation o;
  o.type = ObservationType::kBearing;
  EXPECT_FALSE(o.HasRange());
  EXPECT_TRUE(o.HasBearing());
  o.type = ObservationType::kRangeBearing;
  EXPECT_TRUE(o.HasRange());
  EXPECT_TRUE(o.HasBearing());
}

TEST(MeasurementTypesTest, SimulatorKindNames) {
  ObservationType type;
  std::string error;
  ASSERT_TRUE(ParseMeasurementKind("range_bearing", &type, &error));
  EXPECT_EQ(type, ObservationType::kRangeBearing);
  ASSERT_TRUE(ParseMeasurementKind("rb", &type, &error));
  EXPECT_EQ(type, ObservationType::kRangeBearing);
  ASSERT_TRUE(ParseMeasurementKind("bearing", &type, &error));
  EXPECT_EQ(type, ObservationType::kBearing);
  EXPECT_EQ(MeasurementKindName(ObservationType::kRange), "range");
  EXPECT_FALSE(ParseMeasurementKind("RANGE", &type, &error));
  EXPECT_EQ(error,
            "--kind=RANGE: unknown measurement kind; allowed range, bearing "
            "or range_bearing");
}

// Each type's cost has one residual per measured value, over the pose's
// blocks and the landmark's, and a calibrated range reads the calibration.
TEST(MeasurementTypesTest, CostsHaveARowPerMeasuredValue) {
  Eigen::VectorXd phi = Eigen::VectorXd::Ones(1);
  double calibration[2] = {1.0, 0.0};
  for (const MeasurementType& type : MeasurementTypes()) {
    for (const bool calibrated : {false, true}) {
      PoseMap map;
      map.mean = Eigen::Vector3d::Zero();
      Observation o;
      o.type = type.type;
      o.range = 5.0;
      o.bearing = 0.3;
      o.sigma_range = 0.1;
      o.sigma_bearing = 0.01;
      ObservationResidualInputs inputs;
      inputs.sigma_range = 0.1;
      inputs.sigma_bearing = 0.01;
      inputs.range_calibration = calibrated ? calibration : nullptr;
      std::vector<double*> blocks;
      std::unique_ptr<ceres::CostFunction> cost(
          type.cost(o, map, inputs, &blocks));
      ASSERT_NE(cost, nullptr);
      EXPECT_EQ(cost->num_residuals(), int{type.range} + int{type.bearing})
          << type.record;
      EXPECT_EQ(blocks.size(), calibrated && type.range ? 1u : 0u)
          << type.record;
    }
  }
}

TEST(MeasurementTypesTest, NoiseGroupOfEachResidualRow) {
  EXPECT_EQ(DataRowGroup("range", 0), VarianceGroup::kRange);
  EXPECT_EQ(DataRowGroup("bearing", 0), VarianceGroup::kBearing);
  EXPECT_EQ(DataRowGroup("range-bearing", 0), VarianceGroup::kRange);
  EXPECT_EQ(DataRowGroup("range-bearing", 1), VarianceGroup::kBearing);
  EXPECT_EQ(DataRowGroup("odometry", 2), VarianceGroup::kOdometry);
  EXPECT_EQ(DataRowGroup("landmark prior", 0), VarianceGroup::kFixed);
}

}  // namespace
}  // namespace rff
