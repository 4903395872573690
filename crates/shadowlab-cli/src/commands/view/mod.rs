//! `shadowlab view`: a window showing the scene shaded by a technique, driven by a person,
//! a script (`--script`) or a benchmark (`--benchmark-frames`).
//!
//! The flow: read the script (its errors are the user's, before any window), open the
//! display and the GPU device (no display, or no adapter, is the user's error too), start
//! the background worker that traces the reference, then answer the window's events until
//! asked to quit. Each frame plays the script's next steps or the person's input
//! (`input`, `script`, `play`) into the session (`session`, `fly`) and the panel (`ui`,
//! `panel`), draws the view as `render` would (`frame`) when it changed, and shows it with
//! the error overlay and the panel on the window's GPU surface (`window`, `blit.wgsl`);
//! screenshots read that frame back and write it with the `render` command line of the
//! view (`capture`, `screenshot`, `reproduce`).

mod app;
mod area;
mod benchmark;
mod capture;
mod fly;
mod frame;
mod gpu_shade;
mod input;
mod map_view;
mod panel;
mod param_widgets;
mod play;
mod reference;
mod reproduce;
mod screenshot;
mod script;
mod session;
mod timings;
mod ui;
mod window;

use crate::config::ViewConfig;
use crate::failure::bad_input;
use anyhow::Result;
use app::{App, Driver, ReferenceReady};
use reference::Background;
use session::Session;
use std::collections::VecDeque;
use winit::event_loop::{ControlFlow, EventLoop};

/// Runs `view`.
pub fn run(cfg: ViewConfig) -> Result<()> {
    let driver = match (&cfg.script, cfg.benchmark_frames) {
        (Some(_), Some(_)) => {
            return Err(bad_input(
                "--script and --benchmark-frames cannot be given together",
            ))
        }
        (Some(p), None) => Driver::Script(script::load(p, cfg.force)?),
        (None, Some(n)) => Driver::Benchmark {
            left: n + 1,
            warm_up: true,
            frames: Vec::new(),
            offscreen: cfg.offscreen,
        },
        (None, None) => Driver::Person,
    };
    keep_freed_memory();
    // Offscreen, the GPU is opened before the display and without it (`gpu_without_display`).
    let early = cfg.offscreen.then(gpu_without_display).transpose()?;
    let event_loop = open_display()?;
    event_loop.set_control_flow(ControlFlow::Wait);
    let gpu = match early {
        Some(gpu) => gpu,
        None => open_gpu()?,
    };
    let proxy = event_loop.create_proxy();
    let mut session = Session::new(
        &cfg.setup.scene,
        &cfg.scene_args,
        cfg.setup.camera,
        (&cfg.setup.light, cfg.setup.area.as_ref()),
        &cfg.technique,
        cfg.params.clone(),
    )?;
    session.show.error = cfg.error_overlay;
    let background = Background::default();
    std::thread::scope(|scope| {
        let worker = background.start(scope, &cfg.setup.scene, move || {
            // The window may be gone already; then nobody waits for the reference.
            let _ = proxy.send_event(ReferenceReady);
        });
        let mut app = App::new(session, &background, driver, &cfg.screenshot_dir, gpu);
        let ran = event_loop.run_app(&mut app);
        background.quit();
        let _ = worker.join();
        ran.map_err(|e| anyhow::anyhow!("the window's event loop failed: {e}"))?;
        app.finish()
    })
}

/// The event loop of the display, or the user's error when there is none.
fn open_display() -> Result<EventLoop<ReferenceReady>> {
    let no_display = || {
        std::env::var_os("DISPLAY").is_none_or(|d| d.is_empty())
            && std::env::var_os("WAYLAND_DISPLAY").is_none_or(|d| d.is_empty())
    };
    if no_display() {
        return Err(bad_input(
            "view needs a display and neither DISPLAY nor WAYLAND_DISPLAY is set (on a machine without one, run it under xvfb-run)",
        ));
    }
    EventLoop::<ReferenceReady>::with_user_event()
        .build()
        .map_err(|e| {
            // winit's text starts with its own source location; the reason is the last part.
            let text = e.to_string();
            let reason = text.rsplit(": ").next().unwrap_or(&text).to_string();
            let display = std::env::var("DISPLAY").unwrap_or_default();
            bad_input(format!(
                "view cannot open a window on display {display:?} ({reason}); on a machine without one, run it under xvfb-run"
            ))
        })
}

/// The shared GPU device the window draws with, or the user's error when there is no
/// adapter.
fn open_gpu() -> Result<std::sync::Arc<shadowlab_gpu::device::Gpu>> {
    shadowlab_gpu::device::shared().map_err(|e| match e {
        shadowlab::error::Error::Internal(m) => anyhow::anyhow!("view cannot draw: {m}"),
        e => bad_input(format!("view draws with the GPU and {e}")),
    })
}

/// [`open_gpu`] with `DISPLAY` hidden from the GPU's driver, for `--offscreen`, which
/// draws nothing into the window. NVIDIA's Vulkan driver asks the X server that `DISPLAY`
/// names for GLX; under a bare Xvfb (no GLX) on an H200 the viewer then ended in a
/// segmentation fault, and without a display the driver opens its device headless.
fn gpu_without_display() -> Result<std::sync::Arc<shadowlab_gpu::device::Gpu>> {
    let display = std::env::var_os("DISPLAY");
    // Nothing else reads the environment meanwhile: the reference's worker starts after
    // the window opens, and no other thread of this process touches it.
    std::env::remove_var("DISPLAY");
    let gpu = open_gpu();
    if let Some(d) = display {
        std::env::set_var("DISPLAY", d);
    }
    gpu
}

/// Frames allocate and free the same large buffers again and again (the camera pass, a
/// technique's maps). glibc hands blocks past its thresholds back to the kernel when they
/// are freed, and the kernel zeroes their pages again on the next frame's first touch: a
/// third of `sm`'s frame time went there. The viewer keeps freed memory for the next frame
/// instead; it stays at the largest frame's working set.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn keep_freed_memory() {
    // glibc's largest mmap threshold (DEFAULT_MMAP_THRESHOLD_MAX on 64-bit targets).
    let mmap_max = (4 * 1024 * 1024 * std::mem::size_of::<libc::c_long>()) as libc::c_int;
    // SAFETY: mallopt only sets glibc's allocation thresholds and is thread-safe; a value
    // it refuses leaves the default in place.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, mmap_max);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 1 << 30);
        libc::mallopt(libc::M_TOP_PAD, 64 << 20);
    }
}

/// Elsewhere the allocator's defaults stay.
#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn keep_freed_memory() {}

/// The script steps, for the driver.
pub type Steps = VecDeque<script::Step>;
