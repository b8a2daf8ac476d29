//! The renderer's exact motion, for the temporal difference error (`tde`,
//! `../shared/notes/metrics.md` 3.3): per measured frame, every pixel's screen motion from the
//! previous frame (camera and object motion, from the scene shader's velocity pass) and the valid
//! mask `M_t` (the point was on screen and not hidden in the previous frame).
//!
//! Rendered once per scenario, only when `tde` is asked for, after the timed work of the
//! reference; never between timed frames.

use super::sequence::{history_valid, submit_frame};
use crate::gpu::Gpu;
use crate::render::readback::read_texture;
use crate::render::scene::SceneGpu;
use crate::render::timers::Timers;
use crate::scenario::Scenario;
use crate::techniques::MotionPass;

/// How far the previous frame's depth at the reprojected position may be from the point's own
/// previous depth before the pixel counts as disoccluded: 1% (reversed-Z depth is proportional to
/// 1 / view distance, so this is a 1% relative test on distance too).
pub const DISOCCLUSION_TOLERANCE: f32 = 0.01;

/// One frame's motion from the previous frame, and where it can be trusted.
pub struct MotionField {
    /// Screen motion in pixels, x right, y down, per pixel (row-major).
    pub motion: Vec<[f32; 2]>,
    pub valid: Vec<bool>,
}

/// Motion of every measured frame; `None` where the frame has no previous frame in its shot
/// (the first frame, a camera cut).
pub fn capture(
    gpu: &Gpu,
    scene: &mut SceneGpu,
    scenario: &Scenario,
) -> Result<Vec<Option<MotionField>>, String> {
    let (w, h) = (scenario.width, scenario.height);
    let mut pass = MotionPass::new(gpu, w, h);
    let mut timers = Timers::new(&gpu.device, &[]).map_err(|e| e.to_string())?;
    let mut out = Vec::new();
    let mut prev_depth: Option<Vec<f32>> = None;
    for index in 0..scenario.total_frames() {
        submit_frame(gpu, scene, scenario, pass.renderer(), &mut timers, index);
        let _ = gpu.device.poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: None,
        });
        let _ = timers.try_collect(&gpu.queue);
        if index + 1 < scenario.warmup_frames {
            // Neither this frame's motion nor its depth (the next frame's history) is read.
            continue;
        }
        let depth = read_texture(&gpu.device, &gpu.queue, pass.depth());
        if index >= scenario.warmup_frames {
            let field = match (&prev_depth, history_valid(scenario, index)) {
                (Some(prev), true) => {
                    let velocity = read_texture(&gpu.device, &gpu.queue, pass.motion());
                    Some(field(&velocity, prev, w, h))
                }
                _ => None,
            };
            out.push(field);
        }
        prev_depth = Some(depth);
    }
    Ok(out)
}

/// The motion field from the velocity target (RGBA: motion x, y in pixels, dynamic flag, the
/// point's reversed-Z depth in the previous frame) and the previous frame's depth buffer.
pub fn field(velocity: &[f32], prev_depth: &[f32], width: u32, height: u32) -> MotionField {
    let n = (width * height) as usize;
    let mut motion = Vec::with_capacity(n);
    let mut valid = Vec::with_capacity(n);
    for i in 0..n {
        let v = &velocity[i * 4..i * 4 + 4];
        let m = [v[0], v[1]];
        let x = (i as u32 % width) as f32 + 0.5 - m[0];
        let y = (i as u32 / width) as f32 + 0.5 - m[1];
        let on_screen = m[0].is_finite()
            && m[1].is_finite()
            && x >= 0.0
            && y >= 0.0
            && x < width as f32
            && y < height as f32;
        let visible = on_screen && {
            let j = y as usize * width as usize + x as usize;
            let (a, b) = (v[3], prev_depth[j]);
            (a - b).abs() <= DISOCCLUSION_TOLERANCE * a.max(b)
        };
        motion.push(m);
        valid.push(visible);
    }
    MotionField { motion, valid }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn disocclusion_and_off_screen_are_masked() {
        // 3x1: pixel 0 moved in from off screen; pixel 1 came from pixel 2 whose previous depth
        // matches; pixel 2 came from pixel 1, where something nearer stood last frame.
        let velocity = [
            1.0, 0.0, 0.0, 0.5, //
            -1.0, 0.0, 0.0, 0.25, //
            1.0, 0.0, 1.0, 0.25,
        ];
        let prev_depth = [0.5, 0.5, 0.2501];
        let f = field(&velocity, &prev_depth, 3, 1);
        assert_eq!(f.valid, [false, true, false]);
        assert_eq!(f.motion[2], [1.0, 0.0]);
    }
}
