# The truth (NAME.gt.json) of a clip that scripts/reencode-footage resized by $s and
# from which it left out the file frames $drops (0-based, of the source; [] for none).
# Pixel centres are at integers, so a point c of the source lies at (c + 1/2)·s − 1/2;
# a height above a row scales by s. What is not a pixel measure (the motion, the
# times, the light) stays as it was.
def at(c): (c + 0.5) * $s - 0.5;
def scaled: . * $s;
def maybe(f): if . == null then . else f end;
def without_drops: [to_entries[] | select(.key as $k | $drops | index($k) | not) | .value];

.transform = {scale: $s, dropped_file_frames: $drops}
| .width |= maybe(scaled)
| .height |= maybe(scaled)
| .side_rows |= maybe(map(scaled))
| .plan_rows |= maybe(map(scaled))
| .calibration_rest |= (
    with_entries(
      if (.key | test("^(x_|z_)")) then .value |= at(.)
      elif (.key | test("^px_per_m")) then .value |= scaled
      else . end))
| .cameras |= maybe(map_values(
    .fpx |= maybe(scaled) | .cx |= maybe(at(.)) | .cy |= maybe(at(.))
    | .width |= maybe(scaled) | .height |= maybe(scaled)))
| .true_peaks.z_rim_px |= map(scaled)
| .true_peaks.detectable = [.true_peaks.z_rim_px[] >= 0.5]
| .frames.z_rim_px |= map(maybe(scaled))
| .frames.z_silhouette_px |= maybe(map(maybe(scaled)))
| .fps_nominal as $fps
| .dropped_capture_frames = ((.dropped_capture_frames // [])
    + [.frames.capture_index as $c | $drops[] | $c[.]] | sort)
| .frames |= map_values(without_drops)
| .n_frames = (.frames.index | length)
| .frames.index = [range(0; .n_frames)]
| .frames.t_video = [.frames.index[] / $fps]
| (.halt_frame_video // null) as $h
| if $h then
    .halt_frame_video = $h - ([$drops[] | select(. < $h)] | length)
    | .t0_video = .halt_frame_video / $fps
  else . end
