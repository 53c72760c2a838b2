// The tracker's offline stage (data/tracking.h, LinkDetections): after the
// online pass, fragments of one car are joined and identity switches between
// two cars that came close are undone, each over the whole sequence with a
// constant-velocity fit of every track. Internal to the data layer.
#pragma once

#include <vector>

#include "libsamp/data/track_observation.h"

namespace samp {
struct TrackerOptions;
}

namespace samp::tracking_internal {

// Joins fragment ends to later fragment starts (one-to-one, Hungarian on the
// gated link costs). `tracks` holds observation indices per track, in
// increasing frames. Returns the number of joins.
int JoinFragments(const std::vector<Observation>& observations, const TrackerOptions& o,
                  std::vector<std::vector<int>>* tracks);

// Swaps tails between pairs of tracks while the best swap lowers the sum of
// the two link costs by more than swap_margin. Returns the number of swaps.
int ResolveSwitches(const std::vector<Observation>& observations, const TrackerOptions& o,
                    std::vector<std::vector<int>>* tracks);

}  // namespace samp::tracking_internal
