//! shadowlab on the GPU: a headless `wgpu` device, and shadow techniques whose stages run
//! as WGSL shaders, over the library's scene, camera, light, camera pass, BVH and
//! technique trait.
//!
//! # Design notes
//!
//! The data flow is the library's. The verdict's input is the CPU camera pass
//! ([`shadowlab::view::ViewSamples`], uploaded by [`upload`]), so a `gpu:` technique and its
//! CPU twin are judged on the same samples. A GPU technique implements the library's
//! [`ShadowTechnique`](shadowlab::techniques::ShadowTechnique) and returns the same
//! `Shadows`: the visibility read back, and `Stats` whose stages are wall times (upload,
//! each GPU stage from submission to completion, read-back), whose counters `gpu_STAGE_ms`
//! are the timestamp-query times of the GPU passes, and whose `device` names the adapter
//! (a software adapter's line says `CPU-emulated`). So compare, report, bench and Python
//! need no GPU case beyond the name.
//!
//! A technique runs over a [`resident::DeviceView`]: the camera pass's samples on the
//! device and the few numbers of them a light fit needs on the CPU (covered count, the
//! receivers' bounds). A verdict uploads the library's pass into one; the viewer (and
//! `render --camera-pass gpu`) makes one with the GPU's own pass
//! ([`camera_pass::on_device`]), whose samples never leave the device. So a technique reads
//! nothing per pixel of the frame's CPU samples, unless it says it must
//! ([`resident::OnDevice::needs_cpu_samples`]: `gpu:psm` and `gpu:lispsm` fit their light
//! over every visible point, `gpu:afsm` traces its sub-pixel hits from the pixels); a test
//! runs every other one on a frame that holds none.
//!
//! Layout:
//!
//! ```text
//! device.rs                 adapter choice (--adapter / SHADOWLAB_ADAPTER), limits, faults
//! transfer.rs               buffers up and down, timestamp queries
//! twin.rs                   a GPU technique's parameters are its CPU twin's
//! compute.rs                pipelines and bind groups by binding number, read-back to RGB
//! upload.rs                 scene (per revision), BVH, view samples -> GPU buffers
//! resident.rs               the shadow term left on the device (OnDevice), for the viewer
//! camera_pass/              the GPU's camera pass: the hardware G-buffer (gbuffer.wgsl),
//!                           made into the view samples on the device (samples.wgsl)
//! shader.rs                 the include step composing shaders/common/*.wgsl into stages
//! shaders/common/*.wgsl     written once: watertight test, ray offset, light, alpha masks
//! techniques/maps.rs        what the warped and split maps share: layers of one depth
//!                           array drawn by the rasterizer, the look-up's dispatch
//! techniques/<name>/        one folder per technique, mirroring the library's:
//!   mod.rs                  the ShadowTechnique, its pipelines and dispatches
//!   <stage>.wgsl            one file per stage, named after the stage it runs
//! ```
//!
//! Adding a technique: make `techniques/<name>/mod.rs` with a type implementing
//! `ShadowTechnique` whose `name()` is `gpu:<name>` and whose parameters are its CPU
//! twin's (reuse the twin's `params`/`param_specs`, and [`twin::set_twin_param`]), its
//! stages as `<stage>.wgsl` beside it composed through [`shader::Stage`] with the common
//! files they need, pipelines from [`compute::pipeline`] (made once per device); then add one line to the registry in [`techniques::create`] and its name to
//! [`techniques::ALL`]. Run each stage's GPU work inside [`device::Gpu::stage`] (faults
//! then name the technique and the stage), time passes with [`transfer::Timer`], check
//! sizes against the adapter with [`device::Gpu::check_binding`] /
//! [`device::Gpu::check_texture_side`] before dispatching, and set `stats.device`.
//!
//! Determinism: every pixel is written by one thread, and no result depends on the order
//! threads run (no float atomics; order-independent integer reductions only).
//!
//! Bounded invocations: Mesa's llvmpipe (lavapipe, the CI adapter and the fallback on a
//! machine without a GPU) ends every loop of an invocation, silently, once all the loops
//! of that invocation (of the eight it runs together) have turned 65535 times in total
//! (`LP_MAX_TGSI_LOOP_ITERATIONS`). A stage whose per-thread work grows with the scene (a
//! triangle as large as the map, a texel under thousands of casters) must cut it into
//! items of bounded size: `gpu:afsm`'s triangle–chunk work queue and `gpu:subpixel`'s
//! blocks of rows and chunks of blockers do. It spreads the work over more threads on a
//! hardware GPU too.
//!
//! The library creates these techniques by name once [`register`] has run (the command
//! line and the Python module call it at start), so `gpu:NAME` works wherever a technique
//! is named.

#![forbid(unsafe_code)]

pub mod camera_pass;
pub mod compute;
pub mod device;
pub mod resident;
pub mod shader;
pub mod techniques;
pub mod transfer;
pub mod twin;
pub mod upload;

/// Makes the library's technique registry create the `gpu:` techniques.
pub fn register() {
    shadowlab::techniques::register(shadowlab::techniques::Extension {
        prefix: "gpu:",
        names: techniques::ALL,
        create: techniques::create,
    });
}
