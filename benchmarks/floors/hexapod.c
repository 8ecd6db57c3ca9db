/* Floor for robots/hexapod.yaml: six S-P-S legs with a direct-index threshold
 * (benchmarks/floors/six_legs.h). */
#define ROUTINE kin_hexapod
#define ROUTINE_NAME "kin_hexapod"
#define DIRECT_MIN 6.5
#define REFERENCE_LENGTH 399.413

static const double base[6][3] = {
    { 31.0, 118.156, 40.205 }, { -31.0, 118.156, 40.205 }, { -117.826, -32.231, 40.205 },
    { -86.826, -85.925, 40.205 }, { 86.826, -85.925, 40.205 }, { 117.826, -32.231, 40.205 }
};
static const double platform[6][3] = {
    { 31.0, 48.799, -31.45 }, { -31.0, 48.799, -31.45 }, { -57.761, 2.447, -31.45 },
    { -26.761, -51.246, -31.45 }, { 26.761, -51.246, -31.45 }, { 57.761, 2.447, -31.45 }
};

#include "six_legs.h"
