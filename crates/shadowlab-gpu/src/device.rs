//! The headless device every `gpu:` technique shares: the adapter's choice, its limits,
//! the faults it reports, timestamp queries, and the record of the adapter each result
//! carries.
//!
//! The adapter is the one whose name contains `--adapter NAME` (or `SHADOWLAB_ADAPTER`),
//! case-insensitively; by default the first hardware adapter, else a software one (Mesa's
//! lavapipe). The device is created with the adapter's own limits, so a technique may use
//! all the adapter offers, and [`Gpu::check_binding`] / [`Gpu::check_texture_side`] refuse
//! a request past them before anything is dispatched. One device is made per process, on
//! first use, and shared.
//!
//! Faults: validation, out-of-memory and internal errors are caught in error scopes around
//! each stage ([`Gpu::stage`]) and become an [`Error::Internal`] naming the technique and
//! the stage; a lost device is recorded by its callback (which never panics) and reported
//! the same way. wgpu's default handler for errors outside a scope panics: it is replaced by
//! one that records the message.

use crate::shader::PipelineKey;
use shadowlab::error::{Error, Result};
use std::sync::{Arc, Mutex, OnceLock};

/// The environment variable naming the adapter when `--adapter` is not given.
pub const ADAPTER_ENV: &str = "SHADOWLAB_ADAPTER";

/// What a machine without any adapter should install, in one sentence.
pub const NO_ADAPTER: &str = "no GPU adapter was found: install a Vulkan driver (on Debian, \
    `apt-get install mesa-vulkan-drivers` gives the software adapter lavapipe) or a GPU's own driver";

static CHOICE: OnceLock<String> = OnceLock::new();

/// Chooses the adapter by a substring of its name (the command line's `--adapter`); wins
/// over [`ADAPTER_ENV`]. Only the first call counts.
pub fn choose_adapter(name: &str) {
    let _ = CHOICE.set(name.to_string());
}

/// The adapter substring asked for, if any.
fn asked_for() -> Option<String> {
    CHOICE
        .get()
        .cloned()
        .or_else(|| std::env::var(ADAPTER_ENV).ok())
        .filter(|s| !s.trim().is_empty())
}

/// The adapter a result came from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AdapterRecord {
    /// The adapter's name (`llvmpipe (LLVM 15.0.6, 256 bits)`, `NVIDIA H200`).
    pub name: String,
    /// The backend (`vulkan`, `metal`, `dx12`).
    pub backend: String,
    /// The device type (`discrete`, `integrated`, `virtual`, `cpu`).
    pub device_type: String,
    /// The driver and its version.
    pub driver: String,
    /// True for a software adapter: its times are CPU-emulated, never GPU figures.
    pub software: bool,
}

impl AdapterRecord {
    fn of(info: &wgpu::AdapterInfo) -> Self {
        let device_type = match info.device_type {
            wgpu::DeviceType::DiscreteGpu => "discrete",
            wgpu::DeviceType::IntegratedGpu => "integrated",
            wgpu::DeviceType::VirtualGpu => "virtual",
            wgpu::DeviceType::Cpu => "cpu",
            wgpu::DeviceType::Other => "other",
        };
        let driver = [info.driver.as_str(), info.driver_info.as_str()]
            .iter()
            .filter(|s| !s.is_empty())
            .copied()
            .collect::<Vec<_>>()
            .join(" ");
        AdapterRecord {
            name: info.name.clone(),
            backend: info.backend.to_string().to_lowercase(),
            device_type: device_type.to_string(),
            driver,
            software: info.device_type == wgpu::DeviceType::Cpu,
        }
    }

    /// One line naming the adapter; a software adapter's line says its times are
    /// CPU-emulated.
    pub fn label(&self) -> String {
        let emulated = if self.software { ", CPU-emulated" } else { "" };
        format!(
            "{} ({}, {}, {}{emulated})",
            self.name, self.backend, self.device_type, self.driver
        )
    }
}

/// The shared device.
pub struct Gpu {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// The adapter it came from.
    pub adapter: AdapterRecord,
    /// The instance and adapter, for a window's surface on the same device (the viewer).
    pub instance: wgpu::Instance,
    /// The adapter itself (its surface capabilities).
    pub handle: wgpu::Adapter,
    /// The limits in force: the adapter's own.
    pub limits: wgpu::Limits,
    /// True when stages can be timed with timestamp queries.
    pub timestamps: bool,
    /// Faults reported outside an error scope or by the device-lost callback.
    faults: Arc<Mutex<Vec<String>>>,
    /// Compute pipelines made so far, by stage and entry point: a driver compiles each
    /// shader once per process (lavapipe's LLVM takes seconds for a large one).
    pub(crate) compute: Mutex<Vec<(PipelineKey, wgpu::ComputePipeline)>>,
    /// Render pipelines made so far, by stage.
    pub(crate) render: Mutex<Vec<(PipelineKey, wgpu::RenderPipeline)>>,
}

static SHARED: Mutex<Option<Arc<Gpu>>> = Mutex::new(None);

/// The process's device, made on first use.
pub fn shared() -> Result<Arc<Gpu>> {
    let mut slot = SHARED.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(gpu) = slot.as_ref() {
        return Ok(gpu.clone());
    }
    let gpu = Arc::new(pollster::block_on(Gpu::new())?);
    *slot = Some(gpu.clone());
    Ok(gpu)
}

/// The backends shadowlab asks for: the native ones, not OpenGL (whose compute support is
/// too uneven to judge techniques on).
fn backends() -> wgpu::Backends {
    wgpu::Backends::VULKAN | wgpu::Backends::METAL | wgpu::Backends::DX12
}

/// The adapter asked for, or the first hardware one, else the first software one.
async fn pick_adapter(instance: &wgpu::Instance) -> Result<wgpu::Adapter> {
    let adapters = instance.enumerate_adapters(backends()).await;
    if adapters.is_empty() {
        return Err(Error::Limit(NO_ADAPTER.into()));
    }
    if let Some(want) = asked_for() {
        let key = want.to_lowercase();
        let names: Vec<String> = adapters.iter().map(|a| a.get_info().name).collect();
        return adapters
            .into_iter()
            .find(|a| a.get_info().name.to_lowercase().contains(&key))
            .ok_or_else(|| {
                Error::param(format!(
                    "no GPU adapter's name contains {want:?}: the adapters here are {}",
                    names.join(", ")
                ))
            });
    }
    let hardware = |a: &wgpu::Adapter| a.get_info().device_type != wgpu::DeviceType::Cpu;
    let first_hw = adapters.iter().position(hardware);
    let mut adapters = adapters;
    Ok(adapters.swap_remove(first_hw.unwrap_or(0)))
}

impl Gpu {
    async fn new() -> Result<Gpu> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = backends();
        let instance = wgpu::Instance::new(desc);
        let adapter = pick_adapter(&instance).await?;
        let record = AdapterRecord::of(&adapter.get_info());
        let limits = adapter.limits();
        let timestamps = adapter.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        // Optional features, taken where the adapter has them: timestamps, and the formats
        // the filtered maps sample (filterable 32-bit floats, 16-bit normalized moments).
        let features = adapter.features()
            & (wgpu::Features::TIMESTAMP_QUERY
                | wgpu::Features::FLOAT32_FILTERABLE
                | wgpu::Features::TEXTURE_FORMAT_16BIT_NORM);
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("shadowlab"),
                required_features: features,
                required_limits: limits.clone(),
                ..Default::default()
            })
            .await
            .map_err(|e| {
                Error::Internal(format!(
                    "the GPU adapter {} refused a device: {e}",
                    record.name
                ))
            })?;
        let faults = Arc::new(Mutex::new(Vec::new()));
        let lost = faults.clone();
        device.set_device_lost_callback(move |reason, message| {
            if let Ok(mut f) = lost.lock() {
                f.push(format!("the device was lost ({reason:?}: {message})"));
            }
        });
        let uncaptured = faults.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut f) = uncaptured.lock() {
                f.push(e.to_string());
            }
        }));
        Ok(Gpu {
            device,
            queue,
            adapter: record,
            instance,
            handle: adapter,
            limits,
            timestamps,
            faults,
            compute: Mutex::new(Vec::new()),
            render: Mutex::new(Vec::new()),
        })
    }

    /// Refuses a storage buffer of `bytes` for `what` (a parameter or structure, such as
    /// "the scene's triangles") past the adapter's largest binding, in one sentence.
    pub fn check_binding(&self, what: &str, bytes: u64) -> Result<()> {
        let max = self
            .limits
            .max_storage_buffer_binding_size
            .min(self.limits.max_buffer_size);
        if bytes > max {
            return Err(Error::Limit(format!(
                "{what} need {bytes} bytes in one GPU buffer, over the adapter's limit of {max} \
                 bytes per storage binding ({})",
                self.adapter.name
            )));
        }
        Ok(())
    }

    /// Refuses a square texture of side `side` named by `param` past the adapter's largest
    /// 2D texture, in one sentence.
    pub fn check_texture_side(&self, param: &str, side: u32) -> Result<()> {
        let max = self.limits.max_texture_dimension_2d;
        if side > max {
            return Err(Error::Limit(format!(
                "{param} = {side} is over the adapter's largest texture side, {max} ({})",
                self.adapter.name
            )));
        }
        Ok(())
    }

    /// Runs `f` (which records and submits GPU work for stage `stage` of `technique`) inside
    /// error scopes, waits for the queue, and turns any fault into an error naming both.
    pub fn stage<T>(&self, technique: &str, stage: &str, f: impl FnOnce() -> T) -> Result<T> {
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let internal = self.device.push_error_scope(wgpu::ErrorFilter::Internal);
        let out = f();
        let waited = self.device.poll(wgpu::PollType::wait_indefinitely());
        let errors = [
            pollster::block_on(internal.pop()),
            pollster::block_on(validation.pop()),
            pollster::block_on(oom.pop()),
        ];
        let mut faults: Vec<String> = errors
            .into_iter()
            .flatten()
            .map(|e| e.to_string())
            .collect();
        if let Err(e) = waited {
            faults.push(format!("waiting for the GPU failed: {e}"));
        }
        faults.extend(
            self.faults
                .lock()
                .map(|mut f| f.drain(..).collect::<Vec<_>>())
                .unwrap_or_default(),
        );
        match faults.first() {
            None => Ok(out),
            Some(first) => Err(Error::Internal(format!(
                "{technique}: the GPU failed in stage {stage}: {}",
                first.lines().next().unwrap_or(first).trim()
            ))),
        }
    }

    /// The number of nanoseconds one timestamp tick lasts on this queue.
    pub fn timestamp_period_ns(&self) -> f64 {
        f64::from(self.queue.get_timestamp_period())
    }
}
