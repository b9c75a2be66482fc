//! What a pass last ran on, as one number: the light-space passes (shadow maps, light
//! G-buffers, a fixed VPL set and its visibility) and the screen-space passes that depend
//! only on the camera, the objects and the lights (the G-buffer, the direct light) compare
//! this frame's with the last one's and run only when it changed (issue #53;
//! docs/performance.md, "Passes kept while nothing moves"). Every input goes in exactly:
//! matrices and lights as their bytes, settings by their `Debug` text (which writes every
//! float so that it parses back to the same value).

use std::hash::{DefaultHasher, Hasher};

/// A running hash of a pass's inputs.
#[derive(Clone, Debug, Default)]
pub struct Fingerprint(DefaultHasher);

impl Fingerprint {
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds plain data (matrices, GPU records) by their bytes.
    pub fn pod<T: bytemuck::NoUninit>(mut self, v: &[T]) -> Self {
        self.0.write_usize(v.len());
        self.0.write(bytemuck::cast_slice(v));
        self
    }

    /// Adds a value by its `Debug` text (settings, light descriptions).
    pub fn debug(mut self, v: &impl std::fmt::Debug) -> Self {
        use std::fmt::Write;
        let mut text = String::new();
        // Writing into a String cannot fail.
        let _ = write!(text, "{v:?}");
        self.0.write(text.as_bytes());
        self.0.write_u8(0xff);
        self
    }

    /// Adds integers (sizes, counts, seeds).
    pub fn u64s(mut self, v: &[u64]) -> Self {
        v.iter().for_each(|&x| self.0.write_u64(x));
        self
    }

    /// Adds what a scene's draws put where: each primitive's identity and world matrix.
    pub fn draws(mut self, draws: &[crate::scene::DrawItem]) -> Self {
        self.0.write_usize(draws.len());
        for d in draws {
            self.0.write_usize(d.node);
            self.0.write_usize(d.mesh);
            self.0.write_usize(d.primitive);
            self.0.write(bytemuck::bytes_of(&d.world));
        }
        self
    }

    pub fn finish(&self) -> u64 {
        self.0.finish()
    }
}

pub use crate::counters::Space;

/// The last fingerprint a pass ran on; `None` until it has run, and after its outputs were
/// recreated.
#[derive(Clone, Copy, Debug, Default)]
pub struct LastRun(Option<u64>);

impl LastRun {
    /// Whether the pass must run for inputs `key`: true when they differ from the last run's
    /// (and remembers them), false when its outputs still hold their result. Counts the
    /// outcome in `space`'s counters.
    pub fn needs_run(&mut self, key: u64, space: Space) -> bool {
        let run = self.0 != Some(key);
        self.0 = Some(key);
        crate::counters::note_kept(space, run);
        run
    }

    /// Forgets the last run: the next [`Self::needs_run`] is true (outputs recreated).
    pub fn invalidate(&mut self) {
        self.0 = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_inputs_skip_and_any_change_runs() {
        let key = |m: glam::Mat4, s: &str| Fingerprint::new().pod(&[m]).debug(&s).finish();
        let mut last = LastRun::default();
        let before = crate::counters::now();
        let l = Space::Light;
        assert!(last.needs_run(key(glam::Mat4::IDENTITY, "a"), l), "the first frame runs");
        assert!(!last.needs_run(key(glam::Mat4::IDENTITY, "a"), l), "nothing changed: skipped");
        let moved = glam::Mat4::from_translation(glam::Vec3::new(0.0, 1e-6, 0.0));
        assert!(last.needs_run(key(moved, "a"), l), "a micrometre of motion runs it");
        assert!(last.needs_run(key(moved, "b"), l), "a setting runs it");
        last.invalidate();
        assert!(last.needs_run(key(moved, "b"), l), "recreated outputs run it");
        assert!(!last.needs_run(key(moved, "b"), Space::Screen), "counted apart");
        let d = crate::counters::now() - before;
        assert_eq!((d.light_space_runs, d.light_space_skips), (4, 1));
        assert_eq!((d.screen_space_runs, d.screen_space_skips), (0, 1));
    }
}
