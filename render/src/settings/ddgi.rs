//! The settings of dynamic diffuse global illumination (issue #56 point 3): Majercik,
//! Guertin, Nowrouzezahrai and McGuire, "Dynamic Diffuse Global Illumination with Ray-Traced
//! Irradiance Fields", JCGT 8(2), 2019 (cited as 2019 §n), and Majercik, Marrs, Spjut and
//! McGuire, "Scaling Probe-Based Real-Time Dynamic Global Illumination for Production", JCGT
//! 10(2), 2021 (2021 §n). The passes are in `passes/ddgi/`, the CPU twin in `cpu::ddgi`.

use super::splat::IrradianceReceiver;
use crate::{settings_enum, settings_group};

settings_enum! {
    /// The box the probe grid spans (2019 §3: "a regular grid over the scene").
    pub enum GridFit {
        /// The scene's bounding box.
        Scene = "the scene's box",
        /// The room the camera stands in (`scale::room_box`), the scene's box elsewhere: the
        /// probes where the camera looks, not spread over a whole house.
        Room = "the camera's room",
    }
    default Room
}

settings_group! {
    /// DDGI's probes (2019 §3; 2021 §4–5): the grid, the rays each probe casts per frame, its
    /// octahedral irradiance and distance tiles, their hysteresis, the shading biases, and the
    /// 2021 paper's classification and relocation.
    pub struct DdgiSettings: "ddgi" {
        /// What the grid spans (2019 §3), inset by half a cell so that no probe sits on a wall.
        grid_fit: GridFit = GridFit::Room,
        unit "", symbol "", range 0..=1, cost "free", history true;
        /// Probes along x (2019 §3; the bench's production grid is 16×8×16; 12 a side meets
        /// the box's goal, `docs/quality-real-scenes.md`).
        probes_x: u32 = 12,
        unit "probes", symbol "", range 2..=64, cost "every probe traces its rays each frame", history true;
        /// Probes along y (up).
        probes_y: u32 = 12,
        unit "probes", symbol "", range 2..=64, cost "every probe traces its rays each frame", history true;
        /// Probes along z.
        probes_z: u32 = 12,
        unit "probes", symbol "", range 2..=64, cost "every probe traces its rays each frame", history true;
        /// Rays each probe casts per frame, on a spherical Fibonacci lattice under a new random
        /// rotation every frame (2019 §3.1; the paper's 256 at production, 144 in its figures).
        rays_per_probe: u32 = 128,
        unit "rays", symbol "n", range 16..=1024, cost "one closest-hit ray, its shading and shadow rays each", history true;
        /// Interior texels of a probe's octahedral irradiance tile per side (2019 §3.2: 6,
        /// with a one-texel border: 8×8).
        irradiance_texels: u32 = 6,
        unit "texels", symbol "", range 2..=16, cost "the blend: texels × rays per probe", history true;
        /// Interior texels of a probe's distance tile per side (2019 §3.2: 14, 16×16 with the
        /// border).
        distance_texels: u32 = 14,
        unit "texels", symbol "", range 2..=32, cost "the blend: texels × rays per probe", history true;
        /// The share of a texel's old value kept at each update (2019 §3.3, Eq. 3–4: α = 0.97;
        /// lower follows changes sooner and shows more noise).
        hysteresis: f32 = 0.97,
        unit "", symbol "α", range 0.0..=0.999, cost "free", history false;
        /// A cold grid converges as a running mean. ⚠[ddgi.cold-start] The papers blend with α
        /// from a probe's first frame on (2019 §3.3, Eq. 3–4), so the first frame's rays keep
        /// weight α^k after k frames (0.63 after 16 at α = 0.97) and a new grid shows their
        /// noise for about 1/(1 − α) frames; on, the k-th update keeps min(α, k/(k+1)) of the
        /// old value, an even mean of every frame until that reaches α. Off: as printed.
        running_mean_start: bool = true,
        unit "", symbol "", range 0..=1, cost "free", history false;
        /// The exponent of the distance blend's cosine weight (2019 §3.3, "depth sharpness" 50).
        distance_sharpness: f32 = 50.0,
        unit "", symbol "", range 1.0..=200.0, cost "free", history true;
        /// The longest distance a probe records (misses record it), in grid spacings (the
        /// largest of the three axes; 2019 §3.3 clamps to a distance of the grid's scale).
        max_distance: f32 = 1.5,
        unit "spacings", symbol "", range 0.25..=8.0, cost "free", history true;
        /// The shading point moved along its normal before the probes are weighed, in the
        /// smallest spacing (2021 §4.2: 0.2 · 0.75 · 0.3 = 0.045 of the spacing).
        normal_bias: f32 = 0.045,
        unit "spacings", symbol "", range 0.0..=1.0, cost "free", history false;
        /// The shading point moved toward the eye (2021 §4.2: 0.8 · 0.75 · 0.3 = 0.18).
        view_bias: f32 = 0.18,
        unit "spacings", symbol "", range 0.0..=1.0, cost "free", history false;
        /// Classification (2021 §5.2): a probe whose rays meet back faces more than this share
        /// of the time is inside geometry: inactive, never shading.
        backface_ratio: f32 = 0.25,
        unit "", symbol "", range 0.0..=1.0, cost "free", history true;
        /// Relocation (2021 §5.3): a probe closer than this to a front face moves away from it
        /// (in the smallest spacing).
        min_frontface: f32 = 0.1,
        unit "spacings", symbol "", range 0.0..=0.45, cost "free", history true;
        /// Turn probes inside walls or far from any surface off (2021 §5.2).
        classification: bool = true,
        unit "", symbol "", range 0..=1, cost "one pass over each probe's rays", history true;
        /// Inactive probes do no work but watch. ⚠[ddgi.idle-probes] 2021 §5.2: a probe that
        /// shades nothing is not updated; here each frame an inactive probe casts only 32 rays, on a lattice
        /// of that many, to be classified again, and its tiles are not blended (a probe that
        /// wakes blends into the values it had when it went idle). Off: every probe casts
        /// every ray and is blended, used or not. With classification only.
        skip_inactive: bool = true,
        unit "", symbol "", range 0..=1, cost "saves the idle probes' rays and blends", history true;
        /// Move probes out of walls and away from surfaces (2021 §5.3).
        relocation: bool = true,
        unit "", symbol "", range 0..=1, cost "one pass over each probe's rays", history true;
        /// Infinite bounces (2019 §3.3): a ray's hit adds its albedo times the probes'
        /// irradiance of the previous frame, so every frame adds a bounce. Off: one bounce.
        infinite_bounces: bool = true,
        unit "", symbol "", range 0..=1, cost "one probe lookup per ray", history true;
        /// How each pixel reflects the probes' light. ⚠[ddgi.glossy-receiver] The papers' probes
        /// hold irradiance for diffuse receivers (2019 §1: glossy light is left to other
        /// means); `Glossy` adds the specular lobe lit by the probes' irradiance toward the
        /// mirror direction of the view, SI · E(r)/π (the cosine-weighted mean radiance about r,
        /// with the same eight weights), as the HCB's and Gautron's glossy receivers do.
        receiver: IrradianceReceiver = IrradianceReceiver::Glossy,
        unit "", symbol "", range 0..=1, cost "eight more tile reads per pixel", history false;
    }
}
