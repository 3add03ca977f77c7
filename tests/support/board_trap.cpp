// __builtin_trap() (what SEQSLAM_ASSERT does) must end the run with a TRAP report and
// status 3 instead of hanging (board_trap_fails, board_trap_report).
#include "seqslam/board/board.h"

int main() {
  seqslam::board::console_print("board_trap: trapping now\n");
  __builtin_trap();
  seqslam::board::console_print("NOT REACHED after __builtin_trap\n");
  return 0;
}
