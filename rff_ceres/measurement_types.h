// The landmark observation types. One entry per type ties together its .rffd
// record (docs/FORMAT.md), the kind its residuals are reported under, which
// of range and bearing it measures, and its residual (a functor of costs/).
// The reader and writer, the problem, the noise groups, rff_convert's counts
// and the simulator read this table: a new type is a value of
// ObservationType (types.h), its functor, and one entry in
// measurement_types.cc.
#ifndef RFF_CERES_MEASUREMENT_TYPES_H_
#define RFF_CERES_MEASUREMENT_TYPES_H_

#include <string>
#include <string_view>
#include <vector>

#include "ceres/cost_function.h"
#include "costs/pose_map.h"
#include "rff_ceres/types.h"

namespace rff {

// What the residual of one observation is built with besides the record.
struct ObservationResidualInputs {
  // The record's sigmas times the noise scales learned for their groups.
  double sigma_range = 0.0;
  double sigma_bearing = 0.0;
  // The (scale, offset) block of the range sensor when it is estimated,
  // else nullptr.
  double* range_calibration = nullptr;
  // A RANGE_BEARING record's range is the landmark's depth along the
  // heading (depth_bearing_cost.h) rather than its distance.
  bool range_is_depth = false;
};

// The cost of `o` at the pose `map` over `blocks` (the pose's blocks, then
// the landmark's); it appends any further block it reads.
using ObservationCostFactory =
    ceres::CostFunction* (*)(const Observation& o, PoseMap map,
                             const ObservationResidualInputs& inputs,
                             std::vector<double*>* blocks);

struct MeasurementType {
  ObservationType type;
  // The .rffd record: t id, the measured values (range, then bearing), then
  // their sigmas in the same order. In lower case, rff_simulate's --kind.
  const char* record;
  // The kind of its residuals in reports ("range-bearing"); their rows are
  // the measured values in the record's order.
  const char* kind;
  bool range;
  bool bearing;
  ObservationCostFactory cost;
};

// Every type, in ObservationType order.
const std::vector<MeasurementType>& MeasurementTypes();
const MeasurementType& MeasurementTypeOf(ObservationType type);
// The type of a .rffd record name, or of a residual kind; nullptr if none.
const MeasurementType* FindMeasurementRecord(std::string_view record);
const MeasurementType* FindMeasurementKind(std::string_view kind);

// rff_simulate's --kind: the record in lower case ("range_bearing"), or the
// short form "rb" of the benchmark file names. Returns false and fills
// `error` for anything else.
bool ParseMeasurementKind(const std::string& name, ObservationType* type,
                          std::string* error);
std::string MeasurementKindName(ObservationType type);

}  // namespace rff

#endif  // RFF_CERES_MEASUREMENT_TYPES_H_
