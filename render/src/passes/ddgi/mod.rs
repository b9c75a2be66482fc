//! Dynamic diffuse global illumination on the GPU (issue #56 point 3; Majercik et al. 2019,
//! 2021; CPU twin `cpu::ddgi`). So far the probe update's blend (`blend`): the trace of the
//! probes' rays and the sampling at every pixel, the stage choice, its panel and viewers come
//! next (docs/architecture.md, "Rays on the GPU").

pub mod blend;
