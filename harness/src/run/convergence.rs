//! A variant's declared convergence against the scenario's warm-up: how many frames its history
//! needs (`Technique::convergence`), how many warm-up frames it had, whether the camera moved
//! through them, and whether its measured frames therefore saw a steady history. Pure: reads the
//! scenario, renders nothing.

use tessera_results::Convergence;

use crate::scenario::Scenario;

/// Whether the camera moves between consecutive frames of `frames` (indices into the scenario's
/// frame times).
fn camera_moves(scenario: &Scenario, mut frames: std::ops::Range<u32>) -> bool {
    frames.any(|i| {
        let a = scenario.camera.pose_at(scenario.frame_time(i));
        let b = scenario.camera.pose_at(scenario.frame_time(i + 1));
        a != b
    })
}

/// The record of a variant that needs `frames` frames of history in `scenario`.
pub fn record(scenario: &Scenario, frames: u32) -> Convergence {
    let warmup = scenario.warmup_frames;
    let measured = scenario.measured_frames.max(1);
    let camera_moving_in_warmup = camera_moves(scenario, 0..warmup);
    let camera_moving_in_measured = camera_moves(scenario, warmup..warmup + measured - 1);
    Convergence {
        frames,
        warmup_frames: warmup,
        camera_moving_in_warmup,
        camera_moving_in_measured,
        converged: warmup >= frames && (camera_moving_in_warmup || !camera_moving_in_measured),
    }
}

/// The stderr hint for a result measured before its history was steady, if it was.
pub fn hint(scenario: &str, variant: &str, c: &Convergence) -> Option<String> {
    if c.converged {
        return None;
    }
    let why = if c.warmup_frames < c.frames {
        format!(
            "its history needs {} frames and the warm-up has {}",
            c.frames, c.warmup_frames
        )
    } else {
        "the camera holds still through the warm-up and moves while measured".to_string()
    };
    Some(format!(
        "hint: {scenario} / {variant} was measured before its history was steady ({why}): raise `frames.warmup` to at least {} with the camera track already moving",
        c.frames.max(c.warmup_frames)
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scenario(warmup: u32, track: &str) -> Scenario {
        let src = format!(
            "resolution = [8, 8]\n[frames]\nwarmup = {warmup}\nmeasured = 4\n[camera]\n{track}\n[[techniques]]\ntechnique = \"native\"\n"
        );
        crate::scenario::parse(std::path::Path::new("c.toml"), &src).unwrap()
    }

    const MOVING: &str = "[[camera.keyframes]]\ntime = 0\nposition = [0, 1, 4]\ntarget = [0, 0, 0]\n[[camera.keyframes]]\ntime = 1\nposition = [1, 1, 4]\ntarget = [0, 0, 0]";
    const STILL: &str = "[[camera.keyframes]]\ntime = 0\nposition = [0, 1, 4]\ntarget = [0, 0, 0]";
    // Holds still for the first 0.1 s, then moves.
    const LATE: &str = "[[camera.keyframes]]\ntime = 0.1\nposition = [0, 1, 4]\ntarget = [0, 0, 0]\n[[camera.keyframes]]\ntime = 1\nposition = [1, 1, 4]\ntarget = [0, 0, 0]";

    #[test]
    fn enough_moving_warm_up_converges_and_too_little_says_so() {
        let c = record(&scenario(8, MOVING), 8);
        assert!(c.converged && c.camera_moving_in_warmup && c.camera_moving_in_measured);
        let c = record(&scenario(3, MOVING), 32);
        assert!(!c.converged);
        let h = hint("s", "taau", &c).unwrap();
        assert!(h.contains("needs 32 frames and the warm-up has 3"), "{h}");
        assert!(hint("s", "taau", &record(&scenario(8, MOVING), 8)).is_none());
    }

    #[test]
    fn a_still_warm_up_before_a_moving_measurement_is_not_steady() {
        // At 60 Hz the first 6 frames are inside the hold.
        let c = record(&scenario(4, LATE), 2);
        assert!(!c.camera_moving_in_warmup && c.camera_moving_in_measured);
        assert!(!c.converged);
        assert!(hint("s", "v", &c).unwrap().contains("holds still"));
        // A still camera throughout: a still warm-up is representative.
        let c = record(&scenario(4, STILL), 2);
        assert!(c.converged && !c.camera_moving_in_measured);
    }
}
