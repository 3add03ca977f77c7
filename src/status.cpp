#include "seqslam/status.h"

namespace seqslam {

const char* status_name(Status s) {
  switch (s) {
    case Status::kOk:
      return "OK";
    case Status::kInvalidArgument:
      return "INVALID_ARGUMENT";
    case Status::kOutOfRange:
      return "OUT_OF_RANGE";
    case Status::kResourceExhausted:
      return "RESOURCE_EXHAUSTED";
    case Status::kFailedPrecondition:
      return "FAILED_PRECONDITION";
    case Status::kDataLoss:
      return "DATA_LOSS";
    case Status::kNotFound:
      return "NOT_FOUND";
    case Status::kUnavailable:
      return "UNAVAILABLE";
    case Status::kInternal:
      return "INTERNAL";
  }
  return "UNKNOWN";
}

}  // namespace seqslam
