//! The test process as the camera of a live `dicstream correlator` (frames rendered with the
//! producer crate, published with `wire::pubsub`) and as its field reader, on a [`Run`] (its own
//! instance, children and folders, cleaned even when the test fails).

use super::{Proc, Run, HANG_GUARD};
use producer::motion::Affine;
use producer::Motion;
use std::path::PathBuf;
use std::time::{Duration, Instant};
use wire::pubsub::{SlicePublisher, SliceSubscriber};
use wire::{services, FieldHeader, FieldNode, FrameHeader, GroundTruth};

/// A field copied out of shared memory.
#[derive(Clone, Debug)]
pub struct FieldCopy {
    pub header: FieldHeader,
    pub nodes: Vec<FieldNode>,
}

impl FieldCopy {
    /// Mean and standard deviation of (u - u_true, v - v_true) over the nodes with status ok.
    pub fn error_stats(&self, truth: &GroundTruth) -> [(f64, f64); 2] {
        let ok: Vec<&FieldNode> = self
            .nodes
            .iter()
            .filter(|n| n.status == wire::NodeStatus::Ok as u32)
            .collect();
        let errors: Vec<(f64, f64)> = ok
            .iter()
            .map(|n| {
                let (u, v) = truth.displacement_px(n.x_px as f64, n.y_px as f64);
                (n.u_px as f64 - u, n.v_px as f64 - v)
            })
            .collect();
        let count = errors.len() as f64;
        let stats = |pick: fn(&(f64, f64)) -> f64| {
            let mean = errors.iter().map(pick).sum::<f64>() / count;
            let var = errors.iter().map(|e| (pick(e) - mean).powi(2)).sum::<f64>() / count;
            (mean, var.sqrt())
        };
        [stats(|e| e.0), stats(|e| e.1)]
    }
}

/// The line of a correlator's final summary ("correlator: stopped ...").
pub fn final_line(proc: &Proc) -> String {
    proc.line_starting("correlator: stopped")
        .unwrap_or_else(|| panic!("no final line; stderr:\n{}", proc.stderr()))
}

/// A number that follows `label ` in `line` (e.g. "dropped 12").
pub fn number_after(line: &str, label: &str) -> u64 {
    let at = line
        .find(&format!("{label} "))
        .unwrap_or_else(|| panic!("{label:?} not in {line:?}"));
    line[at + label.len() + 1..]
        .chars()
        .take_while(|c| c.is_ascii_digit())
        .collect::<String>()
        .parse()
        .unwrap_or_else(|_| panic!("no number after {label:?} in {line:?}"))
}

struct Io {
    frames: SlicePublisher<u16, FrameHeader>,
    fields: SliceSubscriber<FieldNode, FieldHeader>,
    // Dropped last: the ports above belong to it.
    _node: iceoryx2::prelude::Node<iceoryx2::prelude::ipc::Service>,
}

/// One test's bench: a [`Run`] (instance, children, scratch folder) with the test as camera
/// and field reader.
pub struct Bench {
    pub run: Run,
    io: Option<Io>,
}

impl Bench {
    /// `test` names the bench; frames up to `max_pixels` values.
    pub fn new(test: &str, max_pixels: usize) -> Bench {
        let run = Run::new(test);
        let (node, _) = run.instance.create_node("testbench").unwrap();
        let frames = SlicePublisher::create(&node, &services::FRAMES, max_pixels).unwrap();
        let fields = SliceSubscriber::create(&node, &services::FIELDS).unwrap();
        Bench {
            run,
            io: Some(Io {
                frames,
                fields,
                _node: node,
            }),
        }
    }

    pub fn name(&self) -> &str {
        self.run.name()
    }

    /// A fresh folder removed with the bench.
    pub fn temp_dir(&mut self, label: &str) -> PathBuf {
        self.run.temp_dir(label)
    }

    /// Starts `dicstream correlator --instance NAME ARGS...`; returns its index.
    pub fn spawn_correlator(&mut self, args: &[&str]) -> usize {
        let name = self.run.name().to_string();
        let mut all = vec!["correlator", "--instance", &name];
        all.extend_from_slice(args);
        self.run.spawn("correlator", &all);
        self.run.children_started() - 1
    }

    pub fn proc(&mut self, index: usize) -> &mut Proc {
        self.run.proc(index)
    }

    /// Publishes one frame; returns how many subscribers received it.
    pub fn send_frame(&self, header: FrameHeader, pixels: &[u16]) -> usize {
        let io = self.io.as_ref().unwrap();
        io.frames
            .publish(pixels.len(), |h, out| {
                *h = header;
                out.copy_from_slice(pixels);
                Ok::<bool, ()>(true)
            })
            .unwrap()
            .unwrap()
            .unwrap()
    }

    /// A consistent header for `pixels` of `width` x `height` (16 bit, with the checksum).
    pub fn header(
        frame_id: u64,
        width: usize,
        height: usize,
        pixels: &[u16],
        truth: Option<GroundTruth>,
    ) -> FrameHeader {
        FrameHeader {
            frame_id,
            t_capture_ns: wire::monotonic_ns(),
            width_px: width as u32,
            height_px: height as u32,
            bit_depth: 16,
            rig_sample_id: 5000 + 7 * frame_id,
            has_truth: truth.is_some() as u32,
            truth: truth.unwrap_or(GroundTruth::IDENTITY),
            pixel_checksum: wire::frame::pixel_checksum(pixels),
            ..FrameHeader::default()
        }
    }

    /// The next field, waiting (bounded) on the fields event.
    pub fn next_field(&self) -> FieldCopy {
        self.try_next_field(HANG_GUARD).unwrap_or_else(|| {
            panic!(
                "no field within {HANG_GUARD:?}; stderr:\n{}",
                self.run.all_stderr()
            )
        })
    }

    pub fn try_next_field(&self, patience: Duration) -> Option<FieldCopy> {
        let io = self.io.as_ref().unwrap();
        let deadline = Instant::now() + patience;
        loop {
            if let Some(sample) = io.fields.receive().unwrap() {
                return Some(FieldCopy {
                    header: *sample.user_header(),
                    nodes: sample.payload().to_vec(),
                });
            }
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return None;
            }
            let _ = io
                .fields
                .listener()
                .timed_wait(|_| {}, left.min(Duration::from_millis(200)));
        }
    }

    /// Fields until the one of `frame_id` (included).
    pub fn fields_until(&self, frame_id: u64) -> Vec<FieldCopy> {
        let mut out = Vec::new();
        loop {
            let field = self.next_field();
            let id = field.header.frame_id;
            out.push(field);
            if id == frame_id {
                return out;
            }
            assert!(id < frame_id, "field of frame {id} after {frame_id}");
        }
    }

    /// Kills what is left, removes the files and asserts nothing of the instance remains.
    pub fn finish(mut self) {
        self.cleanup();
        let left = self.run.instance.leftover_files();
        assert!(left.is_empty(), "left in shared memory: {left:?}");
    }

    /// The children go first, then the test's own ports, then the instance's files.
    fn cleanup(&mut self) {
        self.run.kill_children();
        self.io = None;
        self.run.teardown();
    }
}

impl Drop for Bench {
    fn drop(&mut self) {
        self.cleanup();
    }
}

/// Speckle (producer defaults, seed 1) covering the image plus a margin, moved by `motion`,
/// seen by a 16-bit camera with Gaussian read noise (1 % of full scale) of seed `seed`.
pub fn render(width: usize, height: usize, motion: &Motion, seed: u64) -> Vec<u16> {
    producer::exact_test_frame(width, height, 24.0, motion, 0.01, seed)
}

/// A speckle of another pattern (producer defaults but pattern seed 99), unrelated to the
/// one `render` draws, unmoved, with the same camera.
pub fn unrelated_speckle(width: usize, height: usize, seed: u64) -> Vec<u16> {
    let (ex, ey) = ([-8.0, width as f64 + 8.0], [-8.0, height as f64 + 8.0]);
    let params = producer::SpeckleParams {
        seed: 99,
        ..producer::SpeckleParams::default()
    };
    let speckle = producer::Speckle::new(params, ex, ey);
    let mut pattern = vec![0f32; width * height];
    producer::ExactRenderer {
        gauss_order: 3,
        threads: 2,
    }
    .render(&speckle, &Motion::IDENTITY, width, &mut pattern);
    producer::CameraModel::read_noise_only_16bit(0.01, seed).exposed(seed, &pattern, width, 2)
}

/// An affine motion and the same motion as ground truth for the frame header.
pub fn affine(
    f: [[f64; 2]; 2],
    translation_px: [f64; 2],
    centre_px: [f64; 2],
) -> (Motion, GroundTruth) {
    let motion = Motion::Affine(Affine {
        f,
        translation_px,
        centre_px,
    });
    let truth = GroundTruth {
        deformation_gradient: [f[0][0], f[0][1], f[1][0], f[1][1]],
        translation_px,
        centre_px,
        ..GroundTruth::IDENTITY
    };
    (motion, truth)
}

pub fn translation(u_px: f64, v_px: f64) -> (Motion, GroundTruth) {
    affine([[1.0, 0.0], [0.0, 1.0]], [u_px, v_px], [0.0, 0.0])
}
