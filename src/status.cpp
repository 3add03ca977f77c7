#include "seqslam/status.h"

#include "seqslam/messages.h"

namespace seqslam {

const char* message_code(const char* family, uint32_t value) {
  static char code[2 + 10 + 1];
  char digits[10];
  uint32_t n = 0;
  do {
    digits[n++] = static_cast<char>('0' + value % 10);
    value /= 10;
  } while (value != 0);
  uint32_t i = 0;
  for (; i < 2 && family[i] != '\0'; ++i)
    code[i] = family[i];
  while (n > 0)
    code[i++] = digits[--n];
  code[i] = '\0';
  return code;
}

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
