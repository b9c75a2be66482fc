//! The deterministic clock. Animations and camera paths advance only through it: the
//! time is the number of animated frames times a fixed step, never wall time, so the
//! same scene, settings and frame count give bit-identical images.

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clock {
    /// Frames rendered since start (advances while paused, too).
    pub frame: u64,
    /// Frames of animation time elapsed (advances only while playing or stepping).
    pub anim_frame: u64,
    /// Fixed time step in seconds.
    pub time_step_s: f64,
    pub playing: bool,
}

impl Clock {
    pub fn new(time_step_s: f64) -> Self {
        Self { frame: 0, anim_frame: 0, time_step_s, playing: true }
    }

    /// Animation time in seconds.
    pub fn time_s(&self) -> f32 {
        (self.anim_frame as f64 * self.time_step_s) as f32
    }

    /// Animation time of the previous frame (for the movement buffer).
    pub fn prev_time_s(&self) -> f32 {
        (self.anim_frame.saturating_sub(1) as f64 * self.time_step_s) as f32
    }

    /// Advances after a rendered frame.
    pub fn tick(&mut self) {
        self.frame += 1;
        if self.playing {
            self.anim_frame += 1;
        }
    }

    /// Advances the animation by one step (the app's Step button while paused).
    pub fn step(&mut self) {
        self.anim_frame += 1;
    }
}

impl Default for Clock {
    fn default() -> Self {
        Self::new(1.0 / 60.0)
    }
}
