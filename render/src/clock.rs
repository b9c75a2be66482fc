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
    /// Playback speed (the timeline's speed control): animation seconds per step are
    /// `time_step_s × speed`. 1 keeps time = frames × step exactly.
    pub speed: f64,
    /// Time at `anim_frame` 0 (set by scrubbing and by speed changes so that time is
    /// continuous).
    pub origin_s: f64,
    /// Loop length in seconds (0 = no loop): time wraps to [0, loop_s).
    pub loop_s: f64,
}

impl Clock {
    pub fn new(time_step_s: f64) -> Self {
        Self { frame: 0, anim_frame: 0, time_step_s, playing: true, speed: 1.0, origin_s: 0.0, loop_s: 0.0 }
    }

    fn time_at(&self, anim_frame: u64) -> f64 {
        let t = self.origin_s + anim_frame as f64 * self.time_step_s * self.speed;
        if self.loop_s > 0.0 { t.rem_euclid(self.loop_s) } else { t }
    }

    /// Animation time in seconds.
    pub fn time_s(&self) -> f32 {
        self.time_at(self.anim_frame) as f32
    }

    /// Animation time of the previous frame (for the movement buffer).
    pub fn prev_time_s(&self) -> f32 {
        if self.anim_frame == 0 {
            return self.time_at(0) as f32;
        }
        self.time_at(self.anim_frame - 1) as f32
    }

    /// Jumps to animation time `t` (the timeline's scrubber). Negative times start at 0; a
    /// time that is not a finite number is ignored (the clock stays where it is).
    pub fn seek(&mut self, t: f64) {
        if !t.is_finite() {
            return;
        }
        self.origin_s = t.max(0.0);
        self.anim_frame = 0;
    }

    /// Changes the playback speed without a jump in time; a speed that is not a finite
    /// number is ignored.
    pub fn set_speed(&mut self, speed: f64) {
        if !speed.is_finite() {
            return;
        }
        let now = self.time_at(self.anim_frame);
        self.speed = speed;
        self.seek(now);
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

#[cfg(test)]
mod tests {
    use super::Clock;

    #[test]
    fn speed_seek_and_loop_keep_time_continuous() {
        let mut c = Clock::new(0.5);
        c.tick();
        c.tick();
        assert_eq!(c.time_s(), 1.0);
        c.set_speed(2.0);
        assert_eq!(c.time_s(), 1.0, "a speed change does not jump");
        c.tick();
        assert_eq!(c.time_s(), 2.0);
        assert_eq!(c.prev_time_s(), 1.0);
        c.seek(0.25);
        assert_eq!(c.time_s(), 0.25);
        c.loop_s = 1.0;
        c.tick();
        assert_eq!(c.time_s(), 0.25, "1.25 wraps to 0.25");
        c.seek(f64::NAN);
        c.seek(f64::INFINITY);
        c.set_speed(f64::NAN);
        assert_eq!((c.time_s(), c.speed), (0.25, 2.0), "non-finite seeks and speeds are ignored");
    }
}
