// Symbol-check canary for linked images: double arithmetic makes the linker pull libgcc's
// soft-float routines (__adddf3, ...) into the image, which check-target-symbols.sh must
// report (symbol_check_catches_soft_float*). Linked with firmware.ld, never run.
#include "seqslam/board/board.h"

int main() {
  volatile double a = 1.5;
  volatile double b = 2.25;
  return (a + b) > 3.0 ? 0 : 1;
}
