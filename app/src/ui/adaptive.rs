//! Interactive while tuning (issue #39 point 3): while the user drags (a slider, a light, the
//! camera) or flies, the window lowers the render scale until a frame fits the target frame
//! rate (View → target frame rate, 15 fps by default; 0 turns it off), and puts the full
//! scale back a moment after the gesture ends, so that the temporal passes converge at full
//! resolution when idle. The status bar shows the factor while it is below 1. The CLI never
//! uses it, and the window's tests turn it off (`--no-adaptive-scale`) so that their sizes
//! stay fixed.
//!
//! A frame's cost is taken as proportional to its pixels, so the scale that fits the budget
//! is the current one × √(budget / frame time). The factor moves in steps of
//! [`STEP`] (each change reallocates the render targets), at most halving per change, and
//! the first frames after a change are not measured (they pay for the reallocation).

use std::time::{Duration, Instant};

/// Granularity of the factor.
pub const STEP: f32 = 0.05;
/// The lowest factor.
pub const MIN_FACTOR: f32 = 0.1;
/// How long after the last input the full scale comes back.
pub const SETTLE: Duration = Duration::from_millis(300);
/// Frames after a change that are not measured.
const SKIP_FRAMES: u32 = 2;

#[derive(Clone, Debug)]
pub struct AdaptiveScale {
    /// Multiplies the render scale (1: none).
    pub factor: f32,
    smoothed_ms: f32,
    measured: u32,
    last_input: Option<Instant>,
}

impl Default for AdaptiveScale {
    fn default() -> Self {
        Self { factor: 1.0, smoothed_ms: 0.0, measured: 0, last_input: None }
    }
}

impl AdaptiveScale {
    /// One frame: `interacting` while a gesture is under way, `frame_ms` the last frame's
    /// wall time, `target_fps` the goal (≤ 0: off). Returns the factor for this frame.
    pub fn update(&mut self, interacting: bool, frame_ms: f32, target_fps: f32, now: Instant) -> f32 {
        if target_fps <= 0.0 || !frame_ms.is_finite() {
            self.reset();
            return self.factor;
        }
        if interacting {
            self.last_input = Some(now);
        } else if self.last_input.is_none_or(|t| now.duration_since(t) >= SETTLE) {
            self.reset();
            return self.factor;
        }
        self.measured += 1;
        if self.measured <= SKIP_FRAMES {
            return self.factor;
        }
        self.smoothed_ms =
            if self.measured == SKIP_FRAMES + 1 { frame_ms } else { 0.5 * self.smoothed_ms + 0.5 * frame_ms };
        let budget = 1000.0 / target_fps;
        let ratio = budget / self.smoothed_ms.max(1e-3);
        let wanted = if ratio < 0.9 {
            self.factor * ratio.sqrt().max(0.5)
        } else if ratio > 1.5 && self.factor < 1.0 {
            self.factor * ratio.sqrt().min(1.25)
        } else {
            self.factor
        };
        let next = ((wanted / STEP).floor() * STEP).clamp(MIN_FACTOR, 1.0);
        if (next - self.factor).abs() >= STEP * 0.5 {
            self.factor = next;
            self.measured = 0;
        }
        self.factor
    }

    fn reset(&mut self) {
        self.factor = 1.0;
        self.measured = 0;
        self.smoothed_ms = 0.0;
        self.last_input = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_slow_gesture_lowers_the_scale_to_the_budget_and_idle_restores_it() {
        let mut a = AdaptiveScale::default();
        let t0 = Instant::now();
        // A frame of 400 ms at full scale, its cost ∝ pixels (factor²), target 15 fps.
        let mut t = t0;
        for _ in 0..40 {
            let ms = 400.0 * a.factor * a.factor;
            a.update(true, ms, 15.0, t);
            t += Duration::from_millis(ms as u64);
        }
        let fitted = 400.0 * a.factor * a.factor;
        assert!(fitted <= 1000.0 / 15.0 / 0.9, "the frame fits the budget: {fitted} ms at {}", a.factor);
        assert!(a.factor >= 0.3, "without going lower than needed: {}", a.factor);
        // Still within the settling time: the factor stays.
        assert_eq!(a.update(false, fitted, 15.0, t + Duration::from_millis(100)), a.factor);
        // After it, the full scale.
        assert_eq!(a.update(false, fitted, 15.0, t + SETTLE + Duration::from_millis(200)), 1.0);
        // Off: always 1.
        let mut b = AdaptiveScale::default();
        for _ in 0..10 {
            assert_eq!(b.update(true, 1000.0, 0.0, t0), 1.0);
        }
    }

    #[test]
    fn a_fast_frame_is_not_lowered() {
        let mut a = AdaptiveScale::default();
        let t = Instant::now();
        for _ in 0..20 {
            assert_eq!(a.update(true, 20.0, 15.0, t), 1.0);
        }
    }
}
