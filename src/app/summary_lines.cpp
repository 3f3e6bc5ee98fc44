#include "summary_lines.hpp"

#include <cstdio>

namespace rgbdtam {

void print_loop_summary(const SlamSystem& system) {
  if (!system.loop_enabled()) return;
  const LoopCounters& l = system.loop().counters();
  const TrackingCounters& c = system.tracking().counters();
  std::printf(
      "loop: %u places (the store keeps %d; %u forgotten); %u views aligned with theirs: %u "
      "revisit edges (loops), %u covisible edges; %u window edges, %u reuse edges; %u corrections "
      "(%u adopted, %u blended into the poses sent, %u dropped; %u poses withheld after them); %u "
      "relocalised (%u on a new keyframe, %u at places older than the dense pool); %u keyframes "
      "dropped at the queue; ms per keyframe: describe median %.1f, search median %.1f p95 %.1f, "
      "pose graph max %.1f\n",
      l.keyframes, system.places().capacity(), system.places().evicted(), l.candidates,
      l.revisit_edges, l.covisible_edges, l.window_edges, l.reuse_edges, l.corrections,
      c.loop_corrections, c.blended_corrections, l.corrections_dropped, c.withheld, c.relocalised,
      c.relocalised_on_new_keyframe, c.relocalised_past_the_pool, c.loop_dropped_keyframes,
      system.loop().describe_time().percentile_ms(0.5),
      system.loop().search_time().percentile_ms(0.5),
      system.loop().search_time().percentile_ms(0.95), system.loop().optimise_time().max_ms());
}

void warn_about_depth(const TrackingPipeline& tracking, const char* program) {
  const TrackingCounters c = tracking.counters();
  const DepthUnitsReading& units = tracking.depth_units_off();
  if (c.depth_units_off > 0) {
    std::fprintf(stderr,
                 "%s: error: %u frames' depth was not in the sensor's units, and no pose was "
                 "sent from them: the steps between its values are %.2f times those of the "
                 "configured sensor (depth.baseline %.3f m, depth.focal %.0f px, "
                 "depth.disparity_quantum %.3f px); at depth.factor %.0f they would fit, where it "
                 "is %.0f\n",
                 program, c.depth_units_off, units.step_ratio, tracking.params().sensor.baseline_m,
                 tracking.params().sensor.depth_focal_px,
                 tracking.params().sensor.disparity_quantum_px, units.fitting_factor,
                 tracking.params().sensor.depth_factor);
  }
  if (c.depth_frozen == 0 && c.without_depth * 2 <= c.frames) return;
  std::fprintf(stderr,
               "%s: warning: %u of %u frames had no usable depth (%u repeated the last depth "
               "frame, %u were not a surface; the others had none delivered or none within "
               "depth.min..depth.max): check the sensor, its depth units and depth.factor\n",
               program, c.without_depth, c.frames, c.depth_frozen, c.depth_not_surface);
}

}  // namespace rgbdtam
