//! The simulated disk over the footage (`compare`): `model-overlay.mp4`, the
//! model's outline drawn on every frame of the span, `model-last-turns.png`, the
//! last turns side by side (footage | model), and the overlay's own error, the
//! image-space distance between the model's and the footage's rim edge on the
//! centre band, per frame (`model-overlay.csv`) and summarised.
//!
//! The model's state at a measured instant t (halt at 0) is its trajectory at
//! model time t + lead ([`crate::compare`]'s convention), through
//! [`trajectory_motion`] (the renderer's: angles by Hermite interpolation, the
//! centre of mass integrated and placed to rest at the origin, flat after its
//! end). A side view does not see the precession's phase or sense: the phase is
//! set so that the model's contact point is straight behind its centre (ψ ≡ −π/2,
//! where z_rim peaks) at the measured peaks, by their circular mean; and when the
//! plan view showed the mirror sense (`beta_sign` = −1) the model is mirrored.
//! Its outline is the convex hull of both rims projected by the camera of
//! [`CameraPose`] (the silhouette of a cylinder). Its rim edge on the centre band
//! is ray cast as the renderer casts its ground truth
//! ([`crate::render::rim_edge_row`]): on each of the band's columns, the lowest
//! row whose ray through the calibrated camera first meets the disk's white
//! surfaces (the side face or the top; what the footage's white edge is while the
//! rim is off the plate), averaged over the band's columns as the footage's
//! z_rim is read on them.

use std::path::Path;

use image::{Rgb, RgbImage};
use serde::Serialize;

use super::OverlayError;
use super::canvas::{text_lines, yuv420_of};
use super::measured::{
    Layout, OVERLAY_H264, OverlaySpec, decode_positions, last_turns, peak_positions,
};
use super::pose::CameraPose;
use crate::analyse::{Experiment, ExperimentPlan, FrameRecord};
use crate::compare::Comparison;
use crate::footage::{FrameSource, FrameView};
use crate::output::{write_atomic, write_csv, write_through_temporary};
use crate::render::H264Writer;
use crate::render::motion::{DiskState, Motion, trajectory_motion};
use crate::render::rim_edge_row;
use crate::render::scene::{Camera, DiskShape, Pose};

/// The video's name in the comparison folder.
pub const MODEL_OVERLAY_VIDEO: &str = "model-overlay.mp4";
/// The side-by-side sheet's name.
pub const MODEL_LAST_TURNS_IMAGE: &str = "model-last-turns.png";
/// The per-frame error table's name.
pub const MODEL_OVERLAY_ERRORS: &str = "model-overlay.csv";

const MODEL: Rgb<u8> = Rgb([255, 140, 0]);
const RIM: Rgb<u8> = Rgb([0, 255, 0]);
const TEXT: Rgb<u8> = Rgb([235, 235, 235]);
/// Points per rim of the model's outline.
const RIM_POINTS: usize = 96;

/// Summary statistics of the per-frame rim-edge distance.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct EdgeError {
    /// Frames with both edges.
    pub frames: usize,
    /// Mean model − footage \[px\] (positive: the model's edge lower in the image,
    /// its rim nearer the plate).
    pub mean_px: f64,
    /// RMS \[px\].
    pub rms_px: f64,
    /// Largest |model − footage| \[px\].
    pub max_abs_px: f64,
    /// The same in metres, at the near rim's scale δ \[m\].
    pub mean_m: f64,
    pub rms_m: f64,
    pub max_abs_m: f64,
}

/// What [`write_model_overlay`] wrote and found.
#[derive(Debug, Clone, Serialize)]
pub struct ModelOverlay {
    pub video: String,
    pub last_turns: Option<String>,
    pub errors_csv: String,
    /// The camera pose the model was drawn with.
    pub pose: CameraPose,
    /// Added to the model's ψ so that its rim peaks at the measured peaks \[rad\].
    pub psi_offset_rad: f64,
    /// Whether the model was mirrored to the footage's sense of precession.
    pub mirrored: bool,
    /// The model's rim edge against the footage's, on the centre band.
    pub edge_error: Option<EdgeError>,
}

#[derive(Serialize, Default)]
struct ErrorRow {
    index: usize,
    t_s: f64,
    footage_edge_row_px: f64,
    model_edge_row_px: f64,
    error_px: f64,
    error_m: f64,
}

/// The model's image at one instant: its outline (side-view px, `vision`'s
/// convention) and its rim edge's row on the centre line.
struct ModelImage {
    hull: Vec<(f64, f64)>,
    edge_row: Option<f64>,
}

/// Writes the model overlay of comparison `c` of experiment `e` into `dir`.
///
/// # Errors
/// The trajectory cannot be sampled at the footage's frames, the clip cannot be
/// decoded again, the encoder fails or a file cannot be written.
pub fn write_model_overlay(
    dir: &Path,
    e: &Experiment,
    c: &Comparison,
    spec: &OverlaySpec,
) -> Result<ModelOverlay, OverlayError> {
    let plan = &e.plan;
    let track = ModelTrack::new(e, c, spec)?;
    let (span, z_max) = span_of(e, spec, &track)?;
    let layout = Layout::new(plan, z_max);
    let pose = CameraPose::from_calibration(plan, silhouette_top(e)?);
    let (psi_offset, mirrored) = (track.psi_offset, track.mirrored);
    let frames = ModelFrames {
        e,
        view: ModelView::new(plan, &pose, track),
        layout,
        span,
        turns: last_turns(e, &peak_positions(e), spec.last_turns),
        name: format!("{:?} (η = {:.3e})", c.options.model, c.eta),
    };
    let video = dir.join(MODEL_OVERLAY_VIDEO);
    let (tiles, rows) = frames.encode(&video, spec.playback_fps)?;
    write_csv(&dir.join(MODEL_OVERLAY_ERRORS), &rows)?;
    let last_turns = if tiles.is_empty() {
        None
    } else {
        let sheet =
            side_by_side(&tiles, &layout, frames.view.origin).map_err(draw_error(&plan.clip, 0))?;
        let bytes = crate::output::png_bytes(&sheet)
            .map_err(|err| encode_error(&video)(err.to_string()))?;
        write_atomic(&dir.join(MODEL_LAST_TURNS_IMAGE), &bytes)?;
        Some(MODEL_LAST_TURNS_IMAGE.to_string())
    };
    Ok(ModelOverlay {
        video: MODEL_OVERLAY_VIDEO.into(),
        last_turns,
        errors_csv: MODEL_OVERLAY_ERRORS.into(),
        pose,
        psi_offset_rad: psi_offset,
        mirrored,
        edge_error: edge_error(&rows),
    })
}

/// A failure to draw frame `frame` of `clip`, with its reason.
fn draw_error(clip: &Path, frame: usize) -> impl Fn(String) -> OverlayError + '_ {
    move |reason: String| OverlayError::Draw {
        clip: clip.to_path_buf(),
        frame,
        reason,
    }
}

/// A failure to write the video at `path`, with its reason.
fn encode_error(path: &Path) -> impl Fn(String) -> OverlayError + '_ {
    |reason: String| OverlayError::Encode {
        path: path.to_path_buf(),
        reason,
    }
}

/// The model on the footage's clock: its trajectory sampled on the frame grid
/// (model time t + lead at the experiment's time t), and how it is placed against
/// the footage, which sees neither the precession's phase nor its sense.
struct ModelTrack {
    motion: Motion,
    lead: f64,
    fps: f64,
    /// Added to the model's ψ so that its contact point is straight behind its
    /// centre (ψ ≡ −π/2, where z_rim peaks) at the measured peaks, by their
    /// circular mean \[rad\].
    psi_offset: f64,
    /// Whether the plan view showed the mirror sense (`beta_sign` = −1).
    mirrored: bool,
}

impl ModelTrack {
    /// The trajectory of `c` as a motion on `e`'s frame grid, reaching two frames
    /// past the span's end or the model's, whichever is later, and its placement.
    fn new(e: &Experiment, c: &Comparison, spec: &OverlaySpec) -> Result<Self, OverlayError> {
        let plan = &e.plan;
        let fps = plan.fps.fps;
        let lead = c.options.lead_s;
        let end = c.trajectory.end_time();
        let after = (lead + spec.span_s.1 - end).max(0.0) + 2.0 / fps;
        let motion = trajectory_motion(&plan.disk, &c.trajectory, 0.0, c.mu, fps, after, None)
            .map_err(|err| draw_error(&plan.clip, 0)(err.to_string()))?;
        let mut track = ModelTrack {
            motion,
            lead,
            fps,
            psi_offset: 0.0,
            mirrored: c.measured.beta_sign < 0.0,
        };
        let peaks: Vec<f64> = e
            .series
            .peaks
            .peaks
            .iter()
            .filter(|p| p.t + lead <= end)
            .filter_map(|p| Some(-std::f64::consts::FRAC_PI_2 - track.state_at(p.t)?.psi))
            .collect();
        track.psi_offset = peaks
            .iter()
            .map(|d| d.sin())
            .sum::<f64>()
            .atan2(peaks.iter().map(|d| d.cos()).sum::<f64>());
        Ok(track)
    }

    /// The model's state at the experiment's time t (model time t + lead, a frame
    /// of the motion's grid, which starts at model time 0); the last state after
    /// the motion's end, none before its start.
    fn state_at(&self, t: f64) -> Option<&DiskState> {
        let k = ((t + self.lead) * self.fps).round();
        let states = &self.motion.states;
        (k >= 0.0).then(|| &states[(k as usize).min(states.len() - 1)])
    }
}

/// The positions in [`Experiment::frames`] of the first and last frame of the
/// span that the model reaches, and the highest rim among the span's frames
/// \[px\] (the band window's height).
fn span_of(
    e: &Experiment,
    spec: &OverlaySpec,
    track: &ModelTrack,
) -> Result<((usize, usize), f64), OverlayError> {
    let in_span: Vec<usize> = (0..e.frames.len())
        .filter(|&k| (spec.span_s.0..=spec.span_s.1).contains(&e.frames[k].t))
        .filter(|&k| track.state_at(e.frames[k].t).is_some())
        .collect();
    let (Some(&first), Some(&last)) = (in_span.first(), in_span.last()) else {
        return Err(OverlayError::EmptySpan {
            clip: e.plan.clip.clone(),
            from: spec.span_s.0.max(-track.lead),
            to: spec.span_s.1,
        });
    };
    let z_max = in_span
        .iter()
        .filter_map(|&k| e.frames[k].z_rim_px)
        .fold(0.0, f64::max);
    Ok(((first, last), z_max))
}

/// The model as the side camera sees it: its track, the calibrated camera, the
/// cylinder drawn and the centre band its rim edge is read on.
struct ModelView<'a> {
    plan: &'a ExperimentPlan,
    track: ModelTrack,
    camera: Camera,
    disk: DiskShape,
    /// The centre band's side-view columns.
    band: (usize, usize),
    /// The centre line's column, the mirror's axis \[px\].
    x_centre: f64,
    /// The side view's origin in the frame \[px\].
    origin: (f64, f64),
}

impl<'a> ModelView<'a> {
    fn new(plan: &'a ExperimentPlan, pose: &CameraPose, track: ModelTrack) -> Self {
        let (ox, oy) = plan.side_view_origin();
        let x_centre = plan.calibration.calibration.x_centre();
        ModelView {
            plan,
            track,
            camera: pose.camera(plan),
            disk: outline(plan),
            band: crate::vision::band(x_centre, plan.band_half_width_px, plan.side_view_width()),
            x_centre,
            origin: (ox as f64, oy as f64),
        }
    }

    /// The model's outline and rim edge at the experiment's time t; `None` before
    /// the model starts.
    fn image_at(&self, t: f64) -> Option<ModelImage> {
        let plan = self.plan;
        let s = self.track.state_at(t)?;
        let pose = Pose::rolling(
            &plan.disk,
            s.psi + self.track.psi_offset,
            s.phi,
            s.theta,
            s.centre[0],
            s.centre[1],
        );
        let mirrored = self.track.mirrored;
        let points: Vec<(f64, f64)> = (0..2 * RIM_POINTS)
            .map(|k| {
                let a = std::f64::consts::TAU * (k % RIM_POINTS) as f64 / RIM_POINTS as f64;
                let z = if k < RIM_POINTS { -1.0 } else { 1.0 } * plan.disk.half_thickness;
                let (x, row) = project(
                    &self.camera,
                    pose.world_from_body([
                        plan.disk.radius * a.cos(),
                        plan.disk.radius * a.sin(),
                        z,
                    ]),
                );
                let x = if mirrored { 2.0 * self.x_centre - x } else { x };
                (x, row)
            })
            .collect();
        let hull = convex_hull(points);
        let mirror = mirrored.then_some(self.x_centre);
        let edge_row = band_edge_row(&self.disk, &self.camera, &pose, self.band, mirror);
        Some(ModelImage { hull, edge_row })
    }

    /// Draws, in the side window and (twice as thick) in the band window, the
    /// footage's rim edge (green, `footage_row`) and the model's outline and rim
    /// edge (orange).
    fn draw_edges(
        &self,
        image: &mut RgbImage,
        layout: &Layout,
        footage_row: Option<f64>,
        model: Option<&ModelImage>,
    ) {
        let (ox, oy) = self.origin;
        let x_centre = self.x_centre;
        for (window, width) in [(&layout.side, 1.0), (&layout.band, 2.0)] {
            if let Some(row) = footage_row {
                window.row_line(
                    image,
                    row + oy,
                    (x_centre + ox - 4.0, x_centre + ox + 4.0),
                    width,
                    RIM,
                );
            }
            if let Some(m) = model {
                for (a, b) in m.hull.iter().zip(m.hull.iter().cycle().skip(1)) {
                    window.segment(image, (a.0 + ox, a.1 + oy), (b.0 + ox, b.1 + oy), MODEL);
                }
                if let Some(row) = m.edge_row {
                    window.row_line(
                        image,
                        row + oy,
                        (x_centre + ox - 4.0, x_centre + ox + 4.0),
                        width,
                        MODEL,
                    );
                }
            }
        }
    }
}

/// A frame of the last turns kept for the side-by-side sheet, with the model's
/// image at its time.
type Tile = (RgbImage, Option<ModelImage>);

/// The model overlay's frames: what each is drawn from.
struct ModelFrames<'a> {
    e: &'a Experiment,
    view: ModelView<'a>,
    layout: Layout,
    /// The positions in [`Experiment::frames`] of the span's first and last frame.
    span: (usize, usize),
    /// The positions of the last turns' frames.
    turns: Vec<usize>,
    /// The model and its η, for the caption.
    name: String,
}

impl ModelFrames<'_> {
    /// Encodes the span's frames into `video` (through a temporary file, renamed
    /// into place when complete), keeping the last turns' tiles and each frame's
    /// rim-edge error where both edges are found.
    fn encode(
        &self,
        video: &Path,
        playback_fps: f64,
    ) -> Result<(Vec<Tile>, Vec<ErrorRow>), OverlayError> {
        let (e, layout) = (self.e, &self.layout);
        let encode_err = encode_error(video);
        write_through_temporary(video, |partial| {
            let mut writer = H264Writer::create(
                partial,
                layout.width,
                layout.height,
                playback_fps,
                OVERLAY_H264,
            )
            .map_err(&encode_err)?;
            let mut planes = Default::default();
            let mut tiles = Vec::new();
            let mut rows = Vec::new();
            decode_positions(e, self.span, layout, |position, view| {
                let record = &e.frames[position];
                let (image, model, error) = self.draw(record, view)?;
                rows.extend(error);
                if self.turns.contains(&position) {
                    tiles.push((image.clone(), model));
                }
                yuv420_of(&image, &mut planes);
                let [y, u, v] = &planes;
                writer.push_yuv420([y, u, v]).map_err(&encode_err)?;
                Ok(true)
            })?;
            writer.finish().map_err(&encode_err)?;
            Ok::<_, OverlayError>((tiles, rows))
        })
    }

    /// One frame: the footage's windows with both rim edges and the model's
    /// outline drawn, and the caption; the model's image, and the rim-edge error
    /// when both edges are found.
    fn draw(
        &self,
        record: &FrameRecord,
        view: &FrameView,
    ) -> Result<(RgbImage, Option<ModelImage>, Option<ErrorRow>), OverlayError> {
        let plan = self.view.plan;
        let mut image = self.layout.paint(view);
        let footage_row = record.z_rim_px.map(|z| plan.rim_edge_row(z));
        let model = self.view.image_at(record.t);
        self.view
            .draw_edges(&mut image, &self.layout, footage_row, model.as_ref());
        let error = footage_row.zip(model.as_ref().and_then(|m| m.edge_row));
        let row = error.map(|(f, m)| ErrorRow {
            index: record.index,
            t_s: record.t,
            footage_edge_row_px: f,
            model_edge_row_px: m,
            error_px: m - f,
            error_m: (m - f) * plan.metres_per_px,
        });
        let lines = caption(record, &self.name, error, plan.metres_per_px);
        text_lines(&mut image, (8, 4), 14, &lines).map_err(draw_error(&plan.clip, record.index))?;
        Ok((image, model, row))
    }
}

/// A frame's caption: its number and time and the model's name, the rim-edge
/// error `edges` (footage's row, model's row) in px and mm, and the colours' key.
fn caption(
    record: &FrameRecord,
    name: &str,
    edges: Option<(f64, f64)>,
    metres_per_px: f64,
) -> [(String, Rgb<u8>); 3] {
    [
        (
            format!(
                "frame {}  t − t_φ = {:+.1} ms   model: {name}",
                record.index,
                1e3 * record.t
            ),
            TEXT,
        ),
        (
            match edges {
                Some((f, m)) => format!(
                    "rim edge: model − footage = {:+.2} px ({:+.3} mm)",
                    m - f,
                    1e3 * (m - f) * metres_per_px
                ),
                None => "rim edge: not on both".into(),
            },
            TEXT,
        ),
        (
            "orange: the model's outline and rim edge · green: the footage's rim edge".into(),
            Rgb([150, 150, 150]),
        ),
    ]
}

/// The disk the model is drawn as: the plan's cylinder (no strip; its rims
/// sharp, as the outline and the ray cast of the rim edge read only the cylinder).
fn outline(plan: &ExperimentPlan) -> DiskShape {
    DiskShape {
        radius: plan.disk.radius,
        half_thickness: plan.disk.half_thickness,
        beta0: 0.0,
        strip_half_width: 0.0,
        edge_radius: 0.0,
    }
}

/// Image point of a world point in `vision`'s convention (the camera's + 0.5).
fn project(camera: &Camera, p: [f64; 3]) -> (f64, f64) {
    let (x, row) = camera.project(p);
    (x + 0.5, row + 0.5)
}

/// The silhouette's top on the centre line at rest: the plan's, measured on the
/// rest frames ([`crate::vision::silhouette_top`]), else (results written before it
/// was recorded) read the same way on the clip's last frame.
fn silhouette_top(e: &Experiment) -> Result<f64, OverlayError> {
    let plan = &e.plan;
    let c = &plan.calibration.calibration;
    if let Some(top) = plan.scale.silhouette_top_px {
        return Ok(top);
    }
    let (ox, oy) = plan.side_view_origin();
    let mut source = FrameSource::open(&plan.clip)?;
    // The clip's last frame (a decoded span's frames are numbered in the clip),
    // sought by its listed time where the container lists one.
    let last = e.frames.last().map_or(0, |f| f.index);
    match source.stream_index()? {
        Some(index) if last < index.container_times_s.len() => source.seek_frame(last, &index)?,
        _ => source.seek(last)?,
    }
    let top = source.next_frame()?.and_then(|frame| {
        let rows = (c.z_t.ceil().max(0.0) as usize + 1).min(frame.view.height.saturating_sub(oy));
        let side = frame.view.crop(ox, oy, plan.side_view_width(), rows)?;
        crate::vision::silhouette_top(&side, c)
    });
    Ok(top.unwrap_or(c.z_t))
}

/// The convex hull (Andrew's monotone chain), counter-clockwise in image axes.
fn convex_hull(mut points: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    points.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let cross = |o: (f64, f64), a: (f64, f64), b: (f64, f64)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    let mut hull: Vec<(f64, f64)> = Vec::with_capacity(points.len() + 1);
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &(f64, f64)>> = if pass == 0 {
            Box::new(points.iter())
        } else {
            Box::new(points.iter().rev())
        };
        for &p in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

/// The model's rim edge on the centre band `(b0, b1)` (side-view columns
/// b0..b1): the mean over the columns' centres of the lowest row whose ray meets
/// a white surface of `disk` at `pose` ([`rim_edge_row`]), in `vision`'s
/// convention (the camera's + 0.5); `mirror` about that column when the model is
/// drawn mirrored. `None` when no column's rays meet the disk.
fn band_edge_row(
    disk: &DiskShape,
    camera: &Camera,
    pose: &Pose,
    (b0, b1): (usize, usize),
    mirror: Option<f64>,
) -> Option<f64> {
    let rows: Vec<f64> = (b0..b1)
        .filter_map(|column| {
            let x = column as f64 + 0.5;
            let x = mirror.map_or(x, |m| 2.0 * m - x);
            rim_edge_row(disk, camera, x - 0.5, pose)
        })
        .collect();
    (!rows.is_empty()).then(|| 0.5 + rows.iter().sum::<f64>() / rows.len() as f64)
}

fn edge_error(rows: &[ErrorRow]) -> Option<EdgeError> {
    if rows.is_empty() {
        return None;
    }
    let n = rows.len() as f64;
    let mean_px = rows.iter().map(|r| r.error_px).sum::<f64>() / n;
    let rms_px = (rows.iter().map(|r| r.error_px * r.error_px).sum::<f64>() / n).sqrt();
    let max_abs_px = rows.iter().map(|r| r.error_px.abs()).fold(0.0, f64::max);
    let scale = rows[0].error_m / rows[0].error_px;
    let scale = if scale.is_finite() { scale } else { 0.0 };
    Some(EdgeError {
        frames: rows.len(),
        mean_px,
        rms_px,
        max_abs_px,
        mean_m: mean_px * scale,
        rms_m: rms_px * scale,
        max_abs_m: max_abs_px * scale,
    })
}

/// The last turns side by side: each row the footage's side window with the
/// model drawn over it, and the model alone (its silhouette filled white on the
/// dark plate, the plate line red), at the same place and scale.
fn side_by_side(
    tiles: &[(RgbImage, Option<ModelImage>)],
    layout: &Layout,
    (ox, oy): (f64, f64),
) -> Result<RgbImage, String> {
    let side = layout.side;
    let (w, h) = side.canvas_size();
    let header = side.dst_y;
    let gap = 6;
    let title = 30;
    let width = gap + 2 * (w + gap);
    let height = title + tiles.len() as u32 * (h + header + gap) + gap;
    let mut sheet = RgbImage::from_pixel(width, height, Rgb([250, 250, 250]));
    for (k, (image, model)) in tiles.iter().enumerate() {
        let y = title + k as u32 * (h + header + gap);
        let footage =
            image::imageops::crop_imm(image, 0, 0, w.min(image.width()), h + header).to_image();
        image::imageops::replace(&mut sheet, &footage, i64::from(gap), i64::from(y));
        let mut render = RgbImage::from_pixel(w, h + header, Rgb([20, 20, 20]));
        if let Some(model) = model {
            for py in 0..h {
                for px in 0..w {
                    let (fx, fy) = side.to_frame(f64::from(px) + 0.5, f64::from(header + py) + 0.5);
                    if inside(&model.hull, (fx - ox, fy - oy)) {
                        render.put_pixel(px, header + py, Rgb([238, 238, 238]));
                    }
                }
            }
        }
        text_lines(&mut render, (8, 4), 14, &[("model".to_string(), TEXT)])?;
        image::imageops::replace(&mut sheet, &render, i64::from(2 * gap + w), i64::from(y));
    }
    text_lines(
        &mut sheet,
        (8, 6),
        16,
        &[(
            "The last turns: footage with the model's outline | the model alone".into(),
            Rgb([20, 20, 20]),
        )],
    )?;
    Ok(sheet)
}

/// Whether a point lies inside a convex polygon.
fn inside(hull: &[(f64, f64)], p: (f64, f64)) -> bool {
    let mut sign = 0.0;
    for (a, b) in hull.iter().zip(hull.iter().cycle().skip(1)) {
        let c = (b.0 - a.0) * (p.1 - a.1) - (b.1 - a.1) * (p.0 - a.0);
        if c != 0.0 {
            if sign == 0.0 {
                sign = c.signum();
            } else if c.signum() != sign {
                return false;
            }
        }
    }
    hull.len() >= 3
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analyse::analyse_clip;
    use crate::config::ExperimentConfig;

    /// On the committed rendered fixture (a side camera at ε = 3°, orthographic,
    /// power-law motion; its truth gives each frame's pose and z_rim on the centre
    /// column), the model overlay's rim edge for the true pose, ray cast through
    /// the camera found at calibration on the centre band's columns, lies on the
    /// true z_rim: within 0.05 px on every frame where the rim is off the plate.
    /// This checks the pose from the calibration, the cast and the conventions
    /// (the camera's pixel centres, the band, the zero row) together.
    #[test]
    fn ray_cast_rim_edge_of_the_true_pose_lies_on_the_true_z_rim() {
        let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures");
        let clip = fixtures.join("side-dark-n050.mp4");
        let e = analyse_clip(&clip, &fps_480(), &|_, _| {}).unwrap();
        let pose = calibrated_pose(&e);
        assert_eq!(pose.distance_m, None, "a distant camera is orthographic");
        let errors = cast_errors(&e, &fixtures.join("side-dark-n050.truth.json"), &pose);
        // 0.003 px at worst at this revision; the calibration's sub-pixel rows and
        // the band's mean over its columns (against the truth's centre column) may
        // move it, a shift of the pixel convention (0.5) may not.
        assert_all_within(&errors, 0.05);
    }

    /// The same through a close pinhole: a clip rendered here (H.264 at the
    /// default crf) by a camera 0.25 m from the disk's near rim at 10° (a phone
    /// held close: the perspective factor 1.15), whose pose the calibration finds
    /// as a pinhole (0.29 m, 7.6°: the elevation from the top face's ellipse
    /// assumes an orthographic view of it). The rim edge cast for each frame's
    /// true pose lies on the true z_rim within 0.1 px (0.06 px at this revision)
    /// on every frame where the rim is off the plate; the same calibration cast
    /// orthographically is up to 0.8 px off, so the pinhole is what holds it.
    ///
    /// At 3° from 0.25 m (the camera 2.4 mm above the top face, which is then 3.7
    /// px tall) the same holds: the calibration's fitted three-level profile finds
    /// the near top rim on so thin a face (before it, z_t lay on the far top rim,
    /// 3.6 px above, and the cast was up to 0.43 px off).
    #[test]
    fn ray_cast_rim_edge_through_a_close_pinhole_lies_on_the_true_z_rim() {
        for elevation_deg in [10.0, 3.0] {
            cast_through_a_close_pinhole(elevation_deg);
        }
    }

    fn cast_through_a_close_pinhole(elevation_deg: f64) {
        use crate::render::{
            DEFAULT_ENCODING, Plate, RenderSpec, Renderer, test_motion, write_clip,
        };
        let dir = tempfile::tempdir().unwrap();
        let motion = test_motion(480.0, 0.5, 0.15);
        let mut spec = RenderSpec::thesis(Plate::Dark, false);
        (spec.width, spec.height) = (480, 320);
        spec.camera_distance_m = Some(0.25);
        spec.elevation_deg = elevation_deg;
        let renderer = Renderer::new(&spec, &motion).unwrap();
        let written =
            write_clip(&renderer, &dir.path().join("close.mp4"), DEFAULT_ENCODING).unwrap();
        let e = analyse_clip(&written.clip, &fps_480(), &|_, _| {}).unwrap();
        let pose = calibrated_pose(&e);
        let distance = pose.distance_m.expect("a close camera is a pinhole");
        assert!(
            (0.2..0.35).contains(&distance),
            "{elevation_deg}°: distance {distance:.3} m, rendered 0.25 m"
        );
        let errors = cast_errors(&e, &written.truth, &pose);
        assert_all_within(&errors, 0.1);
        let orthographic = CameraPose {
            distance_m: None,
            ..pose
        };
        let worst = cast_errors(&e, &written.truth, &orthographic)
            .iter()
            .map(|(_, error)| error.abs())
            .fold(0.0, f64::max);
        assert!(
            worst > 0.3,
            "{elevation_deg}°: an orthographic camera is {worst:.3} px off at most: the clip \
             does not test perspective"
        );
    }

    fn fps_480() -> ExperimentConfig {
        toml::from_str("fps = 480").unwrap()
    }

    /// The camera pose the model overlay draws `e` with.
    fn calibrated_pose(e: &Experiment) -> CameraPose {
        CameraPose::from_calibration(&e.plan, silhouette_top(e).unwrap())
    }

    /// For each frame of `truth` (the rendered clip's) whose rim is more than half
    /// a pixel off the plate: t and the rim edge ray cast on the centre band for
    /// the frame's true pose through `pose`'s camera, less the row of the true
    /// z_rim [px].
    fn cast_errors(e: &Experiment, truth: &Path, pose: &CameraPose) -> Vec<(f64, f64)> {
        let truth: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(truth).unwrap()).unwrap();
        let plan = &e.plan;
        let camera = pose.camera(plan);
        let disk = outline(plan);
        let band = crate::vision::band(
            plan.calibration.calibration.x_centre(),
            plan.band_half_width_px,
            plan.width,
        );
        let mut errors = Vec::new();
        for frame in truth["frames"].as_array().unwrap() {
            let angle = |k: &str| frame[k].as_f64().unwrap();
            // A rim within half a pixel of the plate meets the plate's mirror
            // image in the footage, not the model's ray cast.
            let Some(z) = frame["z_rim_px"].as_f64().filter(|&z| z > 0.5) else {
                continue;
            };
            let pose = Pose::rolling(
                &plan.disk,
                angle("psi"),
                angle("phi"),
                angle("theta"),
                0.0,
                0.0,
            );
            let row = band_edge_row(&disk, &camera, &pose, band, None).expect("on the band");
            errors.push((angle("t"), row - plan.rim_edge_row(z)));
        }
        errors
    }

    /// Every error within `tolerance` px, over more than 100 frames.
    fn assert_all_within(errors: &[(f64, f64)], tolerance: f64) {
        for &(t, error) in errors {
            assert!(
                error.abs() < tolerance,
                "t = {t:.4} s: the cast rim edge is {error:+.3} px off the true z_rim's row"
            );
        }
        let worst = errors.iter().map(|(_, e)| e.abs()).fold(0.0, f64::max);
        eprintln!(
            "{} frames: the cast within {worst:.3} px of the true z_rim",
            errors.len()
        );
        assert!(errors.len() > 100, "{} frames checked", errors.len());
    }

    /// A square's hull is its corners.
    #[test]
    fn hull_of_a_square() {
        let points = vec![(0.0, 0.0), (2.0, 0.0), (1.0, 1.0), (2.0, 2.0), (0.0, 2.0)];
        let hull = convex_hull(points);
        assert_eq!(hull.len(), 4, "{hull:?}");
        assert!(inside(&hull, (1.0, 1.5)) && !inside(&hull, (3.0, 1.0)));
    }
}
