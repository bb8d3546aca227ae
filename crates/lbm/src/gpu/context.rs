//! Adapter discovery and device creation (wgpu).

use thiserror::Error;

/// Why the GPU backend could not start or run.
#[derive(Debug, Error)]
pub enum GpuError {
    /// No compute-capable adapter was found.
    #[error("no GPU adapter found (wgpu saw none on Vulkan); install a Vulkan driver (a GPU driver, or Mesa's `mesa-vulkan-drivers` for the lavapipe CPU device) or run with `--backend cpu`")]
    NoAdapter,
    /// f64 was asked for on an adapter without `SHADER_F64`.
    #[error("adapter `{adapter}` does not support 64-bit floats in shaders (SHADER_F64); run with `--precision f32` or `--backend cpu`")]
    NoF64 {
        /// Adapter name.
        adapter: String,
    },
    /// FP16 storage was asked for on an adapter without `SHADER_F16`.
    #[error("adapter `{adapter}` does not support 16-bit floats in shaders (SHADER_F16); use `gpu_storage = \"native\"`")]
    NoF16 {
        /// Adapter name.
        adapter: String,
    },
    /// The lattice does not fit the adapter's limits even split over 9 bindings.
    #[error("lattice too large for adapter `{adapter}`: {what}; use more ranks (each rank holds one slab) or `--backend cpu`")]
    TooLarge {
        /// Adapter name.
        adapter: String,
        /// The limit that was exceeded.
        what: String,
    },
    /// The device could not be created.
    #[error("could not open GPU device `{adapter}`: {message}")]
    Device {
        /// Adapter name.
        adapter: String,
        /// wgpu's message.
        message: String,
    },
    /// A read-back from the device failed.
    #[error("GPU read-back failed: {0}")]
    Map(String),
}

/// One adapter as `grainflow info` lists it.
#[derive(Debug, Clone)]
pub struct AdapterSummary {
    /// Adapter name.
    pub name: String,
    /// Graphics API (Vulkan, …).
    pub backend: String,
    /// Discrete GPU, integrated GPU, CPU, …
    pub device_type: String,
    /// Driver name and version.
    pub driver: String,
    /// Whether shaders may use f64.
    pub f64: bool,
    /// Whether shaders may use f16 (for FP16 population storage).
    pub f16: bool,
    /// Largest storage binding (bytes).
    pub max_storage_binding: u64,
    /// Largest buffer (bytes).
    pub max_buffer: u64,
    /// Storage buffers per shader stage.
    pub max_storage_buffers: u32,
}

fn instance() -> wgpu::Instance {
    wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env())
}

fn summary(a: &wgpu::Adapter) -> AdapterSummary {
    let info = a.get_info();
    let limits = a.limits();
    AdapterSummary {
        name: info.name,
        backend: format!("{:?}", info.backend),
        device_type: format!("{:?}", info.device_type),
        driver: format!("{} {}", info.driver, info.driver_info),
        f64: a.features().contains(wgpu::Features::SHADER_F64),
        f16: a.features().contains(wgpu::Features::SHADER_F16),
        max_storage_binding: limits.max_storage_buffer_binding_size,
        max_buffer: limits.max_buffer_size,
        max_storage_buffers: limits.max_storage_buffers_per_shader_stage,
    }
}

/// Every adapter wgpu finds, in its order.
pub fn list_adapters() -> Vec<AdapterSummary> {
    let inst = instance();
    pollster::block_on(inst.enumerate_adapters(wgpu::Backends::all()))
        .iter()
        .map(summary)
        .collect()
}

/// An open device: the adapter's real limits are requested (the defaults cap a storage
/// binding at 128 MiB), plus `SHADER_F64` when offered.
pub struct GpuContext {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// What was opened.
    pub adapter: AdapterSummary,
    /// The device's limits (the adapter's).
    pub limits: wgpu::Limits,
}

impl GpuContext {
    /// Open an adapter. Discrete GPUs come first, then integrated, then CPU devices (Mesa
    /// lavapipe). With several GPUs per node, MPI ranks on a node take them round-robin by
    /// local rank (`OMPI_COMM_WORLD_LOCAL_RANK`, `SLURM_LOCALID`); `GRAINFLOW_GPU_ADAPTER=i`
    /// picks adapter i of `grainflow info` explicitly.
    pub fn open() -> Result<Self, GpuError> {
        let inst = instance();
        let adapters = pollster::block_on(inst.enumerate_adapters(wgpu::Backends::all()));
        let rank_of = |t: wgpu::DeviceType| match t {
            wgpu::DeviceType::DiscreteGpu => 0,
            wgpu::DeviceType::IntegratedGpu => 1,
            wgpu::DeviceType::VirtualGpu => 2,
            wgpu::DeviceType::Cpu => 3,
            wgpu::DeviceType::Other => 4,
        };
        let adapter = if let Some(i) = env_usize("GRAINFLOW_GPU_ADAPTER") {
            adapters.into_iter().nth(i)
        } else {
            let best = adapters
                .iter()
                .map(|a| rank_of(a.get_info().device_type))
                .min();
            let mut same: Vec<wgpu::Adapter> = adapters
                .into_iter()
                .filter(|a| Some(rank_of(a.get_info().device_type)) == best)
                .collect();
            let local = env_usize("OMPI_COMM_WORLD_LOCAL_RANK")
                .or_else(|| env_usize("SLURM_LOCALID"))
                .unwrap_or(0);
            if same.is_empty() {
                None
            } else {
                let n = same.len();
                Some(same.swap_remove(local % n))
            }
        }
        .ok_or(GpuError::NoAdapter)?;
        let summary = summary(&adapter);
        let limits = adapter.limits();
        let features =
            adapter.features() & (wgpu::Features::SHADER_F64 | wgpu::Features::SHADER_F16);
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("grainflow"),
            required_features: features,
            required_limits: limits.clone(),
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|e| GpuError::Device {
            adapter: summary.name.clone(),
            message: e.to_string(),
        })?;
        Ok(Self {
            device,
            queue,
            adapter: summary,
            limits,
        })
    }

    /// Block until the queue is idle.
    pub fn wait(&self) {
        // An error here means the device was lost; the next map reports it.
        let _ = self.device.poll(wgpu::PollType::wait_indefinitely());
    }

    /// Append `bytes` bytes at the start of `buffer` (a MAP_READ buffer) to `out` (unchanged
    /// on an error). A caller that reads every step keeps `out` between steps (cleared
    /// first), so the read allocates nothing once `out` has grown.
    pub fn read_append(
        &self,
        buffer: &wgpu::Buffer,
        bytes: u64,
        out: &mut Vec<u8>,
    ) -> Result<(), GpuError> {
        let slice = buffer.slice(..bytes);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.wait();
        rx.recv()
            .map_err(|e| GpuError::Map(e.to_string()))?
            .map_err(|e| GpuError::Map(e.to_string()))?;
        out.extend_from_slice(
            &slice
                .get_mapped_range()
                .map_err(|e| GpuError::Map(e.to_string()))?,
        );
        buffer.unmap();
        Ok(())
    }
}

fn env_usize(name: &str) -> Option<usize> {
    std::env::var(name).ok()?.trim().parse().ok()
}
