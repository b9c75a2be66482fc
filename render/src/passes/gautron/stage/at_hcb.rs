//! GI Lab's mix with Nguyen et al. (issue #17 "Mixes"; cached, issue #53): Gautron's
//! hemispheres at the HCB's samples, in chunks of the round's slots (the chunk kernels are
//! `super::super::at_samples`, `shaders/gautron/at_samples.wgsl`).

use crate::counters::prelude::*;

use super::GautronStage;
use crate::buffers::read_storage;
use crate::passes::gautron::CacheState;
use crate::passes::gautron::at_samples::{AtSamplesPass, SampleSet};
use crate::passes::stages::FrameInputs;
use crate::timing::GpuTimer;

impl GautronStage {
    /// GI Lab's mix with Nguyen et al.: a hemisphere at each of the HCB's samples of `set`
    /// (`list`, `counter` from `HcbStage::sample_buffers`: every sample, or with the HCB's
    /// sample cache only the cached ones due for recomputation and the new ones, Nguyen
    /// §5.2–5.3), in chunks of the round's slots; each sample's irradiance goes to its
    /// `light`, and `args` gets the HCB splat's indirect arguments. The CPU records the
    /// chunks, so it needs a bound on the set's size: the sample count of a frame or two ago,
    /// read without waiting (`readback::LateCount`), with 25 % and one chunk of headroom (the
    /// chunks past this frame's count draw and dispatch nothing: their sizes come from the
    /// GPU's count; with the cache most of them are empty, each about a tenth of a full one
    /// on lavapipe — bounding the cache's set by its own late size instead left a third of
    /// the samples unlit in the frames where the camera starts to move). Only while no count
    /// has arrived yet (the stage's first frames) are the commands so far submitted and the
    /// count read back, a wait (issue #38). A frame whose count outgrows the bound (a cut to a
    /// far busier view) leaves its excess samples unlit for that one frame (the cache queues
    /// them again, `hcb/cache.wgsl`). The records are scratch.
    pub fn gather_at_samples(
        &mut self,
        f: &FrameInputs,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
        (list, counter, args): (&wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer),
        set: SampleSet<'_>,
    ) -> Result<u32, String> {
        let ctx = f.ctx;
        let slots = self.prepare(f);
        self.cache_key = None;
        ctx.queue.upload(&self.state, 0, bytemuck::bytes_of(&CacheState::default()));
        let list_len = list.size() / crate::passes::gautron::at_samples::HCB_SAMPLE_BYTES;
        let mode = set.mode();
        let late =
            self.sample_count.get_or_insert_with(|| crate::readback::LateCount::new(ctx, "gautron.sample_count"));
        let n = match late.update(enc, counter) {
            Some(recent) => (recent as u64 + recent as u64 / 4 + slots as u64).min(list_len) as u32,
            None => {
                let done = std::mem::replace(
                    enc,
                    ctx.device
                        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame.after_hcb") }),
                );
                ctx.submit([done.finish()]);
                let words = read_storage(ctx, counter, 4)?;
                (bytemuck::pod_read_unaligned::<u32>(&words[..4]) as u64).min(list_len) as u32
            }
        };
        let chunks = n.div_ceil(slots).max(1);
        self.at_samples.get_or_insert_with(|| AtSamplesPass::new(ctx)).ensure_chunks(ctx, chunks);
        let pass = self.at_samples.as_ref().ok_or("no chunk pass")?;
        let group = pass.group(
            ctx,
            (&self.params, &self.state, &self.slots, &self.records),
            &self.raster_args_binding(),
            (counter, list, args),
            set,
        );
        let (g0, g1) = (&self.create_group(f), &self.gbuffer_group(f));
        for k in 0..chunks {
            timer.scope(ctx, enc, "gautron.create", |e, slot| {
                let mut c = e.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("gautron.at_samples"),
                    timestamp_writes: slot.and_then(|s| s.compute(true, true)),
                });
                pass.begin(&mut c, &group, (mode, k));
                c.set_group(0, g0, &[0]);
                c.set_group(1, g1, &[]);
                c.set_pipe(&self.cameras_pipeline);
                c.dispatch(slots.div_ceil(64), 1, 1);
            });
            timer.scope(ctx, enc, "gautron.hemispheres", |e, slot| {
                let round = Some(crate::passes::gautron::hemisphere::RoundArgs(&pass.round_args));
                self.compute_records(f, e, slot, None, slots, round);
                let mut c = e.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("gautron.at_samples.store"),
                    timestamp_writes: None,
                });
                pass.store(&mut c, &group, (mode, k), slots);
            });
        }
        Ok(n)
    }

    /// With the HCB's sample cache, after its update: the HCB splat's indirect arguments over
    /// the cached samples (`HcbStage::build_after_cache` splats them to find where the build
    /// adds samples; the VPL mixes get them from the gather at the due samples).
    pub fn cached_splat_args(
        &mut self,
        f: &FrameInputs,
        enc: &mut wgpu::CommandEncoder,
        (list, counter, args): (&wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer),
    ) {
        let ctx = f.ctx;
        // Offset 0 of the chunk uniform: `cs_cached_args` reads no chunk index.
        if self.at_samples.is_none() {
            self.at_samples = Some(AtSamplesPass::new(ctx));
        }
        let Some(pass) = self.at_samples.as_ref() else {
            return;
        };
        let group = pass.group(
            ctx,
            (&self.params, &self.state, &self.slots, &self.records),
            &self.raster_args_binding(),
            (counter, list, args),
            SampleSet::All,
        );
        let mut c = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("gautron.at_samples.cached_args"),
            timestamp_writes: None,
        });
        pass.cached_args(&mut c, &group);
    }
}
