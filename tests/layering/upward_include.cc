// Built by layering/UpwardIncludeFails against samp::core only: core sits
// below fit, so this include must not resolve.
#include "libsamp/fit/fitter.h"
