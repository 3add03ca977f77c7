// Canary for scripts/check-core-rules.sh: every line below must be flagged.
#include <vector>
double half(double x) { return x / 2; }
void* grab() { return malloc(4); }
int* make() { return new int(3); }
