// Links the installed static library and runs one call through it.
#include <seqslam/seqslam.h>

int main() {
  seqslam::Odometry odometry;
  return odometry.configure(seqslam::OdometryConfig{}) == seqslam::Status::kOk ? 0 : 1;
}
