#include "rff_ceres/measurement_types.h"

#include <cctype>
#include <utility>

#include "costs/bearing_cost.h"
#include "costs/calibrated_range_cost.h"
#include "costs/depth_bearing_cost.h"
#include "costs/near_landmark_cost.h"
#include "costs/range_bearing_cost.h"
#include "costs/range_cost.h"
#include "glog/logging.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/option_error.h"

namespace rff {
namespace {

ceres::CostFunction* CreateRangeCost(const Observation& o, PoseMap map,
                                     const ObservationResidualInputs& in,
                                     std::vector<double*>* blocks) {
  if (in.range_calibration != nullptr) {
    blocks->push_back(in.range_calibration);
    return new CalibratedRangeCost(std::move(map), o.range, in.sigma_range);
  }
  return new RangeCost(std::move(map), o.range, in.sigma_range);
}

ceres::CostFunction* CreateBearingCost(const Observation& o, PoseMap map,
                                       const ObservationResidualInputs& in,
                                       std::vector<double*>* /*blocks*/) {
  return new BearingCost(std::move(map), o.bearing, in.sigma_bearing);
}

ceres::CostFunction* CreateRangeBearingCost(const Observation& o, PoseMap map,
                                            const ObservationResidualInputs& in,
                                            std::vector<double*>* blocks) {
  // Nearness is judged at the stated sigma: the form of a record stays fixed
  // while its noise scales are learned.
  if (o.range < kNearRangeSigmas * o.sigma_range) {
    return new NearLandmarkCost(std::move(map), o.range, o.bearing,
                                in.sigma_range, in.sigma_bearing,
                                o.sigma_range);
  }
  if (in.range_calibration != nullptr) {
    blocks->push_back(in.range_calibration);
    if (in.range_is_depth) {
      return new CalibratedDepthBearingCost(std::move(map), o.range, o.bearing,
                                            in.sigma_range, in.sigma_bearing);
    }
    return new CalibratedRangeBearingCost(std::move(map), o.range, o.bearing,
                                          in.sigma_range, in.sigma_bearing);
  }
  if (in.range_is_depth) {
    return new DepthBearingCost(std::move(map), o.range, o.bearing,
                                in.sigma_range, in.sigma_bearing);
  }
  return new RangeBearingCost(std::move(map), o.range, o.bearing,
                              in.sigma_range, in.sigma_bearing);
}

std::string Lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(c));
  return text;
}

}  // namespace

// The table: one entry per type, in ObservationType order.
const std::vector<MeasurementType>& MeasurementTypes() {
  static const auto* types = new std::vector<MeasurementType>{
      {ObservationType::kRange, "RANGE", "range", true, false,
       &CreateRangeCost},
      {ObservationType::kBearing, "BEARING", "bearing", false, true,
       &CreateBearingCost},
      {ObservationType::kRangeBearing, "RANGE_BEARING", "range-bearing", true,
       true, &CreateRangeBearingCost},
  };
  return *types;
}

const MeasurementType& MeasurementTypeOf(ObservationType type) {
  const MeasurementType& entry =
      MeasurementTypes().at(static_cast<std::size_t>(type));
  DCHECK(entry.type == type) << "the table is out of ObservationType order";
  return entry;
}

const MeasurementType* FindMeasurementRecord(std::string_view record) {
  for (const MeasurementType& m : MeasurementTypes()) {
    if (record == m.record) return &m;
  }
  return nullptr;
}

const MeasurementType* FindMeasurementKind(std::string_view kind) {
  for (const MeasurementType& m : MeasurementTypes()) {
    if (kind == m.kind) return &m;
  }
  return nullptr;
}

bool ParseMeasurementKind(const std::string& name, ObservationType* type,
                          std::string* error) {
  std::vector<std::string> names;
  for (const MeasurementType& m : MeasurementTypes()) {
    names.push_back(Lower(m.record));
    if (name == names.back()) {
      *type = m.type;
      return true;
    }
  }
  if (name == "rb") {
    *type = ObservationType::kRangeBearing;
    return true;
  }
  *error = OptionError("kind", name, "unknown measurement kind",
                       JoinAlternatives(names));
  return false;
}

std::string MeasurementKindName(ObservationType type) {
  return Lower(MeasurementTypeOf(type).record);
}

bool Observation::HasRange() const { return MeasurementTypeOf(type).range; }

bool Observation::HasBearing() const { return MeasurementTypeOf(type).bearing; }

}  // namespace rff
