// Built by layering/OwnLayerBuilds against samp::core: core's own headers resolve.
#include "libsamp/core/pose.h"

double SampLayeringCheck(double yaw) { return samp::WrapAngle(yaw); }
