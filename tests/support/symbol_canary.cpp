// Symbol-check canary: deliberately uses the heap and soft-float. Built into a static
// library that nothing links; ctest runs scripts/check-target-symbols.sh --archive on it and
// expects violations (symbol_check_catches_violations*). If this ever passes the check, the
// checker is broken.
#include <stddef.h>

extern "C" void* malloc(size_t size);  // no libc here; the declaration is the point

double seqslam_canary_average(const double* values, int count);
double seqslam_canary_average(const double* values, int count) {
  double sum = 0.0;
  for (int i = 0; i < count; ++i) {
    sum += values[i];  // __adddf3
  }
  return count > 0 ? sum * (1.0 / static_cast<double>(count)) : 0.0;  // __muldf3 & co
}

void* seqslam_canary_allocate(size_t size);
void* seqslam_canary_allocate(size_t size) {
  return malloc(size);
}
