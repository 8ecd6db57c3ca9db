/* Floor for robots/flexapod.yaml: six S-P-S legs with a direct-index threshold
 * (benchmarks/floors/six_legs.h). */
#define ROUTINE kin_flexapod
#define ROUTINE_NAME "kin_flexapod"
#define DIRECT_MIN 10.0
#define REFERENCE_LENGTH 376.5

static const double base[6][3] = {
    { -132.5, 26.0, 58.5 }, { 43.733, 127.748, 58.5 }, { 88.767, 101.748, 58.5 },
    { 88.767, -101.748, 58.5 }, { 43.733, -127.748, 58.5 }, { -132.5, -26.0, 58.5 }
};
static const double platform[6][3] = {
    { -48.767, 32.466, -75.0 }, { -3.733, 58.466, -75.0 }, { 52.5, 26.0, -75.0 },
    { 52.5, -26.0, -75.0 }, { -3.733, -58.466, -75.0 }, { -48.767, -32.466, -75.0 }
};

#include "six_legs.h"
