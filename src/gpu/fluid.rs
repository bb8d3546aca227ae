//! [`GpuFluid`]: one rank's lattice on a wgpu device. The populations live on the device
//! for the whole run; only halos (every step, on several ranks), probes, forces, fields
//! and checkpoints cross to the host, when they are asked for.

use super::buffers::{
    cell_groups, job_groups, round16, shader_source, Split, DST_BINDING, SRC_BINDING,
};
use super::context::{GpuContext, GpuError};
use crate::lbm::collision::Collision;
use crate::lbm::d2q9::{CX, CY, Q, W};
use crate::lbm::fields::Fields;
use crate::lbm::lattice::{FaceCondition, Lattice, StepError, FLUID, HALO_DIRS, MAX_SOLID};
use crate::lbm::{FluidBackend, Real};
use crate::scene::GpuStorage;
use decomposition::{Comm, Side};
use std::sync::Arc;

/// Uniform block of the kernels (`Geo` in lbm.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct Geo {
    nx: u32,
    ny: u32,
    stride: u32,
    plane: u32,
    ns: u32,
    _pad0: u32,
    faces: u32,
    peers: u32,
    types_at: u32,
    halo_at: u32,
    out_at: u32,
    _pad: u32,
}

/// Index of the inlet ramp factor in the real parameters (`P_INLET`).
const P_INLET: usize = 10;
/// Check the device's instability flag every this many steps (and before any output).
const CHECK_EVERY: u64 = 64;
/// Steps queued in one submission on a single rank (amortises the submission cost on
/// small lattices; several ranks submit every step because of the halo exchange).
const BATCH: usize = 16;
/// Largest read-back chunk.
const READBACK_BYTES: usize = 64 << 20;

struct Pipelines {
    bulk: wgpu::ComputePipeline,
    list: wgpu::ComputePipeline,
    fill_x: wgpu::ComputePipeline,
    fill_y: wgpu::ComputePipeline,
    pack: wgpu::ComputePipeline,
    unpack: wgpu::ComputePipeline,
    moments_all: wgpu::ComputePipeline,
    moments_list: wgpu::ComputePipeline,
    advance: wgpu::ComputePipeline,
}

/// A cell list bound as group 1.
struct CellList {
    group: wgpu::BindGroup,
    len: usize,
}

/// The fluid solver of one rank on a GPU (see the module docs).
pub struct GpuFluid<T: Real> {
    host: Lattice<T>,
    /// Populations stored as IEEE half (arithmetic stays in `T` = f32).
    f16: bool,
    ctx: Arc<GpuContext>,
    split: Split,
    pops: [Vec<wgpu::Buffer>; 2],
    geo: Geo,
    prm_buf: wgpu::Buffer,
    aux_buf: wgpu::Buffer,
    bad_buf: wgpu::Buffer,
    readback: wgpu::Buffer,
    list_layout: wgpu::BindGroupLayout,
    /// `groups[c]`: current buffer `c` as source, the other as destination.
    groups: [wgpu::BindGroup; 2],
    inner: CellList,
    edge: CellList,
    probes: Option<(Vec<(usize, usize)>, CellList)>,
    pipes: Pipelines,
    nslots: usize,
    /// Per force slot and solid: Σ −2 w_i c_i over the cell's links to that solid (the
    /// rest-state part of the momentum exchange, added on the host in f64).
    rest_force: Vec<[f64; 2]>,
    /// Steps recorded but not yet submitted.
    pending: Option<wgpu::CommandEncoder>,
    pending_steps: usize,
}

fn storage(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn face_code(f: &FaceCondition) -> u32 {
    match f {
        FaceCondition::Periodic => 1,
        FaceCondition::FreeSlip => 2,
        FaceCondition::Outflow => 3,
        FaceCondition::Velocity(_) => 4,
        FaceCondition::Pressure(_) => 5,
        FaceCondition::Wall { .. } | FaceCondition::Exchange => 0,
    }
}

fn to_bytes<T: Real>(values: &[T]) -> Vec<u8> {
    let mut out = vec![0u8; values.len() * T::BYTES];
    for (v, b) in values.iter().zip(out.chunks_exact_mut(T::BYTES)) {
        v.put_le(b);
    }
    out
}

fn from_bytes<T: Real>(bytes: &[u8]) -> Vec<T> {
    bytes.chunks_exact(T::BYTES).map(T::get_le).collect()
}

impl<T: Real> GpuFluid<T> {
    /// Move `host` (initial condition applied, halos filled) onto the device of `ctx`,
    /// storing populations as `pop_storage` says. Precondition: FP16 storage only with `T` = f32
    /// (the scene layer checks).
    pub fn new(
        host: Lattice<T>,
        ctx: Arc<GpuContext>,
        pop_storage: GpuStorage,
    ) -> Result<Self, GpuError> {
        let f16 = pop_storage == GpuStorage::F16;
        assert!(!f16 || T::BYTES == 4, "FP16 storage needs f32 arithmetic");
        if f16 && !ctx.adapter.f16 {
            return Err(GpuError::NoF16 {
                adapter: ctx.adapter.name.clone(),
            });
        }
        let pop_bytes = if f16 { 2 } else { T::BYTES };
        if T::BYTES == 8 && !ctx.adapter.f64 {
            return Err(GpuError::NoF64 {
                adapter: ctx.adapter.name.clone(),
            });
        }
        let dev = &ctx.device;
        let (nx, ny, stride, plane) = (host.nx, host.ny, host.stride, host.plane);
        let split = Split::choose(plane, pop_bytes, &ctx)?;
        let per = split.planes_per_part();
        let usage = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_DST
            | wgpu::BufferUsages::COPY_SRC;
        let make = |label: &str, bytes: u64| {
            dev.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes,
                usage,
                mapped_at_creation: false,
            })
        };
        let part_bytes = round16(per * plane * pop_bytes);
        let pops: [Vec<wgpu::Buffer>; 2] = std::array::from_fn(|b| {
            (0..split.parts)
                .map(|j| make(&format!("populations {b}.{j}"), part_bytes))
                .collect()
        });
        // Geometry: plain-cell bits (cells the CPU runs as bulk), then cell types.
        let words = plane.div_ceil(32);
        let mut geom = vec![0u32; words + plane];
        for (y, row) in host.plan.iter().enumerate() {
            for &(a, b) in &row.bulk {
                for x in a as usize..b as usize {
                    let k = (y + 1) * stride + x + 1;
                    geom[k / 32] |= 1 << (k % 32);
                }
            }
        }
        for (k, &t) in host.types.iter().enumerate() {
            geom[words + k] = t as u32;
        }
        // Cell lists in force-slot order (as on the CPU): per row, special cells then edge
        // cells. Edge cells are computed after the halo exchange.
        let mut inner = vec![[0u32; 2]];
        let mut edge = vec![[0u32; 2]];
        for (y, row) in host.plan.iter().enumerate() {
            let first = host.forces.row_start[y];
            for (j, &x) in row.special.iter().enumerate() {
                let k = (y + 1) * stride + x as usize + 1;
                inner.push([k as u32, (first + j) as u32]);
            }
            let first = first + row.special.len();
            for (j, &x) in row.edge.iter().enumerate() {
                let k = (y + 1) * stride + x as usize + 1;
                edge.push([k as u32, (first + j) as u32]);
            }
        }
        let nslots = host.forces.row_start[ny];
        let ns = host.solids.len();
        let mut rest_force = vec![[0.0f64; 2]; nslots * ns];
        for list in [&inner, &edge] {
            for &[k, slot] in &list[1..] {
                for i in 1..Q {
                    let n =
                        (k as isize - CX[i] as isize - CY[i] as isize * stride as isize) as usize;
                    let t = host.types[n];
                    if t != FLUID && t <= MAX_SOLID {
                        let f = &mut rest_force[slot as usize * ns + t as usize - 1];
                        f[0] -= 2.0 * W[i] * CX[i] as f64;
                        f[1] -= 2.0 * W[i] * CY[i] as f64;
                    }
                }
            }
        }
        inner[0][0] = (inner.len() - 1) as u32;
        edge[0][0] = (edge.len() - 1) as u32;
        let halo_at = nslots * ns * 2;
        let out_at = halo_at + 4 * HALO_DIRS * (ny + 2);
        let aux_values = out_at + 3 * nx * ny;
        let aux_bytes = round16(aux_values * T::BYTES);
        let max_binding = ctx.limits.max_storage_buffer_binding_size;
        if aux_bytes > max_binding || aux_values > u32::MAX as usize {
            return Err(GpuError::TooLarge {
                adapter: ctx.adapter.name.clone(),
                what: format!("field output needs {aux_bytes} bytes in one binding, the limit is {max_binding}"),
            });
        }
        let faces = host
            .faces
            .iter()
            .enumerate()
            .map(|(i, f)| face_code(f) << (8 * i))
            .fold(0, |a, b| a | b);
        let peers = host.halo.peer(Side::Left).is_some() as u32
            | (host.halo.peer(Side::Right).is_some() as u32) << 1;
        let geo = Geo {
            nx: nx as u32,
            ny: ny as u32,
            stride: stride as u32,
            plane: plane as u32,
            ns: ns as u32,
            _pad0: 0,
            faces,
            peers,
            types_at: words as u32,
            halo_at: halo_at as u32,
            out_at: out_at as u32,
            _pad: 0,
        };
        let geo_buf = dev.create_buffer(&wgpu::BufferDescriptor {
            label: Some("geo"),
            size: std::mem::size_of::<Geo>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let prm = Self::real_params(&host);
        let prm_buf = make("parameters", round16(prm.len() * T::BYTES));
        let geom_buf = make("geometry", round16(geom.len() * 4));
        let aux_buf = make("aux", aux_bytes);
        let bad_buf = make("instability", 16);
        let inner_buf = make("special cells", round16(inner.len() * 8));
        let edge_buf = make("edge cells", round16(edge.len() * 8));
        let readback = dev.create_buffer(&wgpu::BufferDescriptor {
            label: Some("read-back"),
            size: round16(READBACK_BYTES.min(part_bytes.max(aux_bytes) as usize)),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let q = &ctx.queue;
        q.write_buffer(&geo_buf, 0, bytemuck::bytes_of(&geo));
        q.write_buffer(&prm_buf, 0, &to_bytes(&prm));
        q.write_buffer(&geom_buf, 0, bytemuck::cast_slice(&geom));
        let counter = host.step as u32;
        q.write_buffer(
            &bad_buf,
            0,
            bytemuck::cast_slice(&[u32::MAX, u32::MAX, counter, 0]),
        );
        q.write_buffer(&inner_buf, 0, bytemuck::cast_slice(&inner));
        q.write_buffer(&edge_buf, 0, bytemuck::cast_slice(&edge));
        // Layouts: group 0 the lattice, group 1 a cell list.
        let mut entries = vec![
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
            storage(1, true),
            storage(2, true),
            storage(3, false),
            storage(4, false),
        ];
        for j in 0..split.parts as u32 {
            entries.push(storage(SRC_BINDING + j, true));
            entries.push(storage(DST_BINDING + j, false));
        }
        let lattice_layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("lattice"),
            entries: &entries,
        });
        let list_layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("cell list"),
            entries: &[storage(0, true)],
        });
        let groups: [wgpu::BindGroup; 2] = std::array::from_fn(|c| {
            let mut e = vec![
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: geo_buf.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: prm_buf.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: geom_buf.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: aux_buf.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: bad_buf.as_entire_binding(),
                },
            ];
            for j in 0..split.parts {
                e.push(wgpu::BindGroupEntry {
                    binding: SRC_BINDING + j as u32,
                    resource: pops[c][j].as_entire_binding(),
                });
                e.push(wgpu::BindGroupEntry {
                    binding: DST_BINDING + j as u32,
                    resource: pops[c ^ 1][j].as_entire_binding(),
                });
            }
            dev.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("lattice"),
                layout: &lattice_layout,
                entries: &e,
            })
        });
        let list_group = |buf: &wgpu::Buffer, len: usize| CellList {
            group: dev.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("cell list"),
                layout: &list_layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: buf.as_entire_binding(),
                }],
            }),
            len,
        };
        let inner = list_group(&inner_buf, inner.len() - 1);
        let edge = list_group(&edge_buf, edge.len() - 1);
        let pipes = Self::pipelines(&ctx, split, f16, &host, &lattice_layout, &list_layout);
        let mut gpu = Self {
            host,
            f16,
            ctx,
            split,
            pops,
            geo,
            prm_buf,
            aux_buf,
            bad_buf,
            readback,
            list_layout,
            groups,
            inner,
            edge,
            probes: None,
            pipes,
            nslots,
            rest_force,
            pending: None,
            pending_steps: 0,
        };
        gpu.upload();
        Ok(gpu)
    }

    /// Real parameters (`prm` in lbm.wgsl): collision, force, inlet, pressures, solid
    /// velocities, Zou–He face velocities (W, E: ny each; S, N: nx each).
    fn real_params(host: &Lattice<T>) -> Vec<T> {
        let p = &host.params;
        let mut v = vec![T::default(); 16];
        v[..10].copy_from_slice(&[
            p.tau0,
            p.magic,
            p.s_e,
            p.s_eps,
            p.s_nu,
            p.s_q,
            p.s_q_magic_weight,
            p.smag_k,
            p.force[0],
            p.force[1],
        ]);
        v[P_INLET] = T::from_f64(host.inlet_scale);
        for (i, f) in host.faces.iter().enumerate() {
            if let FaceCondition::Pressure(d) = f {
                v[11 + i] = T::from_f64(*d);
            }
        }
        for s in &host.solids {
            v.extend(s.velocity.map(T::from_f64));
        }
        for (i, f) in host.faces.iter().enumerate() {
            let n = if i < 2 { host.ny } else { host.nx };
            match f {
                FaceCondition::Velocity(u) => {
                    v.extend(u.iter().flat_map(|c| c.map(T::from_f64)));
                }
                _ => v.extend(std::iter::repeat_n(T::default(), 2 * n)),
            }
        }
        v
    }

    fn pipelines(
        ctx: &GpuContext,
        split: Split,
        f16: bool,
        host: &Lattice<T>,
        lattice: &wgpu::BindGroupLayout,
        list: &wgpu::BindGroupLayout,
    ) -> Pipelines {
        let dev = &ctx.device;
        let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("lbm.wgsl"),
            source: wgpu::ShaderSource::Wgsl(
                shader_source(T::NAME, if f16 { "f16" } else { T::NAME }, split).into(),
            ),
        });
        let layout = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("lbm"),
            bind_group_layouts: &[Some(lattice), Some(list)],
            immediate_size: 0,
        });
        let family = match host.collision {
            Collision::Bgk => 0.0,
            Collision::Trt { .. } => 1.0,
            Collision::Mrt { .. } => 2.0,
        };
        let forced = host.params.force[0] != T::default() || host.params.force[1] != T::default();
        let constants = [
            ("FAMILY", family),
            ("SMAG", host.smagorinsky as u8 as f64),
            ("FORCED", forced as u8 as f64),
        ];
        let make = |entry: &str| {
            dev.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants: &constants,
                    zero_initialize_workgroup_memory: false,
                },
                cache: None,
            })
        };
        Pipelines {
            bulk: make("sweep_bulk"),
            list: make("sweep_list"),
            fill_x: make("fill_halo_x"),
            fill_y: make("fill_halo_y"),
            pack: make("pack_halo"),
            unpack: make("unpack_halo"),
            moments_all: make("moments_all"),
            moments_list: make("moments_list"),
            advance: make("advance_step"),
        }
    }

    /// Copy both host population buffers to the device (start and restart).
    fn upload(&mut self) {
        let per = self.split.planes_per_part() * self.host.plane;
        for b in 0..2 {
            // Device buffer c holds host buffer c (host and device agree on `cur`).
            for (j, buf) in self.pops[b].iter().enumerate() {
                let values = &self.host.buf[b][j * per..(j + 1) * per];
                self.ctx
                    .queue
                    .write_buffer(buf, 0, &self.pops_to_bytes(values));
            }
        }
        self.ctx.queue.submit([]);
    }

    /// Populations as the device stores them.
    fn pops_to_bytes(&self, values: &[T]) -> Vec<u8> {
        if !self.f16 {
            return to_bytes(values);
        }
        values
            .iter()
            .flat_map(|v| half::f16::from_f64(v.to_f64()).to_le_bytes())
            .collect()
    }

    /// Inverse of [`GpuFluid::pops_to_bytes`].
    fn pops_from_bytes(&self, bytes: &[u8]) -> Vec<T> {
        if !self.f16 {
            return from_bytes(bytes);
        }
        bytes
            .chunks_exact(2)
            .map(|b| T::from_f64(half::f16::from_le_bytes([b[0], b[1]]).to_f64()))
            .collect()
    }

    /// Read `bytes` bytes of `buffer` from `offset`, through the read-back buffer in chunks.
    fn download(&self, buffer: &wgpu::Buffer, offset: usize, bytes: usize) -> Vec<u8> {
        let mut out = Vec::with_capacity(bytes);
        let chunk = self.readback.size() as usize;
        let mut at = 0;
        while at < bytes {
            let n = (bytes - at).min(chunk);
            let n4 = n.div_ceil(4) * 4;
            let mut enc = self.ctx.device.create_command_encoder(&Default::default());
            enc.copy_buffer_to_buffer(buffer, (offset + at) as u64, &self.readback, 0, n4 as u64);
            self.ctx.queue.submit([enc.finish()]);
            let data = self
                .ctx
                .read(&self.readback, n4 as u64)
                .unwrap_or_else(|e| panic!("{e}: the GPU device was lost"));
            out.extend_from_slice(&data[..n]);
            at += n;
        }
        out
    }

    fn aux_values(&self, first: usize, count: usize) -> Vec<T> {
        from_bytes(&self.download(&self.aux_buf, first * T::BYTES, count * T::BYTES))
    }

    fn encoder(&self) -> wgpu::CommandEncoder {
        self.ctx.device.create_command_encoder(&Default::default())
    }

    /// Submit the queued steps.
    fn flush(&mut self) {
        if let Some(enc) = self.pending.take() {
            self.ctx.queue.submit([enc.finish()]);
        }
        self.pending_steps = 0;
    }

    /// Record one dispatch of `pipe` with lattice group `g` and cell list `list`.
    fn dispatch(
        &self,
        enc: &mut wgpu::CommandEncoder,
        pipe: &wgpu::ComputePipeline,
        g: usize,
        list: &CellList,
        groups: (u32, u32),
    ) {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(pipe);
        pass.set_bind_group(0, &self.groups[g], &[]);
        pass.set_bind_group(1, &list.group, &[]);
        pass.dispatch_workgroups(groups.0, groups.1, 1);
    }

    fn has_peers(&self) -> bool {
        self.geo.peers != 0
    }

    /// Extract the outgoing halo columns of the current buffer and exchange them with the
    /// neighbours; the received columns are staged in `aux`, ready for `unpack_halo`.
    /// `overlap` is recorded and submitted before the transfer, so it runs on the device
    /// while the messages travel. Returns the exposed wait (s). Collective.
    fn exchange(&mut self, comm: &dyn Comm, overlap: Option<wgpu::CommandEncoder>) -> f64 {
        let rows = self.host.ny + 2;
        let cur = self.host.cur;
        let mut enc = self.encoder();
        self.dispatch(
            &mut enc,
            &self.pipes.pack,
            cur,
            &self.inner,
            job_groups(rows),
        );
        self.ctx.queue.submit([enc.finish()]);
        let out = self.aux_values(self.geo.halo_at as usize, 2 * HALO_DIRS * rows);
        for (s, side) in [Side::Left, Side::Right].into_iter().enumerate() {
            if self.host.halo.peer(side).is_some() {
                let part = &out[s * HALO_DIRS * rows..(s + 1) * HALO_DIRS * rows];
                self.host
                    .halo
                    .send_mut(side)
                    .copy_from_slice(&to_bytes(part));
            }
        }
        if let Some(enc) = overlap {
            self.ctx.queue.submit([enc.finish()]);
        }
        let mut halo = std::mem::take(&mut self.host.halo);
        let waited = halo.exchange(comm, &mut || {});
        self.host.halo = halo;
        let inbox = self.geo.halo_at as usize + 2 * HALO_DIRS * rows;
        for (s, side) in [Side::Left, Side::Right].into_iter().enumerate() {
            if self.host.halo.peer(side).is_some() {
                let at = (inbox + s * HALO_DIRS * rows) * T::BYTES;
                self.ctx
                    .queue
                    .write_buffer(&self.aux_buf, at as u64, self.host.halo.recv(side));
            }
        }
        waited
    }

    /// Fill the exchanged halos of the current buffer (before reading fields). Collective.
    fn refresh_exchange(&mut self, comm: &dyn Comm) {
        if !self.has_peers() {
            return;
        }
        let waited = self.exchange(comm, None);
        self.host.halo_wait_s += waited;
        let mut enc = self.encoder();
        let g = self.host.cur ^ 1;
        self.dispatch(
            &mut enc,
            &self.pipes.unpack,
            g,
            &self.inner,
            job_groups(self.host.ny + 2),
        );
        self.ctx.queue.submit([enc.finish()]);
    }

    /// The first unstable step and cell recorded on the device, if any.
    fn first_bad(&self) -> Option<(u64, usize)> {
        let v = self.download(&self.bad_buf, 0, 8);
        let step = u32::from_le_bytes(v[0..4].try_into().expect("4 bytes"));
        let cell = u32::from_le_bytes(v[4..8].try_into().expect("4 bytes"));
        (step != u32::MAX).then_some((step as u64, cell as usize))
    }

    fn probe_list(&mut self, cells: &[(usize, usize)]) {
        if self.probes.as_ref().is_some_and(|(c, _)| c == cells) {
            return;
        }
        let mut entries = vec![[cells.len() as u32, 0]];
        entries.extend(cells.iter().map(|&(x, y)| [x as u32, y as u32]));
        let buf = self.ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("probe cells"),
            size: round16(entries.len() * 8),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        self.ctx
            .queue
            .write_buffer(&buf, 0, bytemuck::cast_slice(&entries));
        let group = self
            .ctx
            .device
            .create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("probe cells"),
                layout: &self.list_layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: buf.as_entire_binding(),
                }],
            });
        self.probes = Some((
            cells.to_vec(),
            CellList {
                group,
                len: cells.len(),
            },
        ));
    }
}

impl<T: Real> FluidBackend<T> for GpuFluid<T> {
    fn device(&self) -> String {
        let a = &self.ctx.adapter;
        let storage = if self.f16 { ", f16 storage" } else { "" };
        format!(
            "gpu: {} ({}, {}{storage})",
            a.name, a.backend, a.device_type
        )
    }

    fn lattice(&self) -> &Lattice<T> {
        &self.host
    }

    fn stream_collide(&mut self, comm: &dyn Comm) -> Result<(), StepError> {
        let cur = self.host.cur;
        let mut enc = self.pending.take().unwrap_or_else(|| self.encoder());
        let (nx, ny) = (self.host.nx, self.host.ny);
        self.dispatch(
            &mut enc,
            &self.pipes.bulk,
            cur,
            &self.inner,
            cell_groups(nx, ny),
        );
        if self.inner.len > 0 {
            let groups = job_groups(self.inner.len);
            self.dispatch(&mut enc, &self.pipes.list, cur, &self.inner, groups);
        }
        if self.has_peers() {
            // Inner cells run on the device while the halos travel.
            let waited = self.exchange(comm, Some(enc));
            self.host.halo_wait_s += waited;
            enc = self.encoder();
            let rows = job_groups(ny + 2);
            self.dispatch(&mut enc, &self.pipes.unpack, cur ^ 1, &self.inner, rows);
            if self.edge.len > 0 {
                let groups = job_groups(self.edge.len);
                self.dispatch(&mut enc, &self.pipes.list, cur, &self.edge, groups);
            }
        }
        self.dispatch(&mut enc, &self.pipes.advance, cur, &self.inner, (1, 1));
        self.pending = Some(enc);
        self.pending_steps += 1;
        self.host.step += 1;
        self.host.cur ^= 1;
        if self.host.step % CHECK_EVERY == 0 {
            self.check(comm)?;
        }
        Ok(())
    }

    fn update_boundaries(&mut self) {
        // The fill kernels write the destination binding: the group whose destination is
        // the (new) current buffer.
        let g = self.host.cur ^ 1;
        let mut enc = self.pending.take().unwrap_or_else(|| self.encoder());
        let (rows, columns) = (job_groups(self.host.ny), job_groups(self.host.stride));
        // Only faces filled from the interior need a kernel (walls and open faces do not).
        let filled = |f: &FaceCondition| {
            matches!(
                f,
                FaceCondition::Periodic | FaceCondition::FreeSlip | FaceCondition::Outflow
            )
        };
        let faces = &self.host.faces;
        if filled(&faces[0]) || filled(&faces[1]) {
            self.dispatch(&mut enc, &self.pipes.fill_x, g, &self.inner, rows);
        }
        if filled(&faces[2]) || filled(&faces[3]) {
            self.dispatch(&mut enc, &self.pipes.fill_y, g, &self.inner, columns);
        }
        self.pending = Some(enc);
        if self.pending_steps >= BATCH || self.has_peers() {
            self.flush();
        }
    }

    fn set_inlet_scale(&mut self, factor: f64) {
        if factor == self.host.inlet_scale {
            return;
        }
        // Queued steps must still see the old factor.
        self.flush();
        self.host.inlet_scale = factor;
        let v = to_bytes(&[T::from_f64(factor)]);
        self.ctx
            .queue
            .write_buffer(&self.prm_buf, (P_INLET * T::BYTES) as u64, &v);
    }

    fn check(&mut self, comm: &dyn Comm) -> Result<(), StepError> {
        self.flush();
        let bad = self.first_bad();
        if !comm.any(bad.is_some()) {
            return Ok(());
        }
        let mine = match bad {
            Some((step, cell)) => {
                let (x, y) = (cell % self.host.nx, cell / self.host.nx);
                let density = self.sample(&[(x, y)])[0].0;
                vec![step as f64, (self.host.x0 + x) as f64, y as f64, density]
            }
            None => Vec::new(),
        };
        let all = comm.all_gather_f64(&mine);
        Err(StepError {
            step: all[0] as u64,
            x: all[1] as usize,
            y: all[2] as usize,
            density: all[3],
        })
    }

    fn forces(&mut self, comm: &dyn Comm) -> Vec<[f64; 2]> {
        self.flush();
        let n = self.nslots * self.host.solids.len();
        if n > 0 {
            let v = self.aux_values(0, 2 * n);
            let slots = self.host.forces.values.iter_mut().zip(&self.rest_force);
            for ((slot, rest), f) in slots.zip(v.chunks_exact(2)) {
                *slot = [f[0].to_f64() + rest[0], f[1].to_f64() + rest[1]];
            }
        }
        self.host.forces(comm)
    }

    fn sample(&mut self, cells: &[(usize, usize)]) -> Vec<(f64, [f64; 2])> {
        if cells.is_empty() {
            return Vec::new();
        }
        self.flush();
        self.probe_list(cells);
        let (_, list) = self.probes.as_ref().expect("probe list just built");
        let mut enc = self.encoder();
        let pipe = &self.pipes.moments_list;
        self.dispatch(&mut enc, pipe, self.host.cur, list, job_groups(cells.len()));
        self.ctx.queue.submit([enc.finish()]);
        let v = self.aux_values(self.geo.out_at as usize, 3 * cells.len());
        v.chunks_exact(3)
            .map(|m| (m[0].to_f64(), [m[1].to_f64(), m[2].to_f64()]))
            .collect()
    }

    fn fields(&mut self, comm: &dyn Comm) -> Fields {
        self.flush();
        self.refresh_exchange(comm);
        let (nx, ny) = (self.host.nx, self.host.ny);
        let mut enc = self.encoder();
        let pipe = &self.pipes.moments_all;
        self.dispatch(
            &mut enc,
            pipe,
            self.host.cur,
            &self.inner,
            cell_groups(nx, ny),
        );
        self.ctx.queue.submit([enc.finish()]);
        let n = nx * ny;
        let v: Vec<f64> = self
            .aux_values(self.geo.out_at as usize, 3 * n)
            .into_iter()
            .map(T::to_f64)
            .collect();
        Fields {
            nx,
            ny,
            rho: v[..n].to_vec(),
            ux: v[n..2 * n].to_vec(),
            uy: v[2 * n..].to_vec(),
            fluid: (0..n).map(|k| self.host.is_fluid(k % nx, k / nx)).collect(),
        }
    }

    fn export_interior(&mut self) -> Vec<T> {
        self.flush();
        let cur = self.host.cur;
        let per = self.split.planes_per_part() * self.host.plane;
        for j in 0..self.split.parts {
            let bytes = per * if self.f16 { 2 } else { T::BYTES };
            let v = self.pops_from_bytes(&self.download(&self.pops[cur][j], 0, bytes));
            self.host.buf[cur][j * per..(j + 1) * per].copy_from_slice(&v);
        }
        self.host.export_interior()
    }

    fn import_interior(&mut self, data: &[T], step: u64) {
        self.flush();
        self.host.import_interior(data, step);
        let counter = step as u32;
        self.ctx.queue.write_buffer(
            &self.bad_buf,
            0,
            bytemuck::cast_slice(&[u32::MAX, u32::MAX, counter, 0]),
        );
        self.upload();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn geo_matches_the_wgsl_layout() {
        assert_eq!(std::mem::size_of::<Geo>(), 48);
    }

    #[test]
    fn bytes_round_trip() {
        let v = [1.5f32, -2.25, 3.0e-7];
        assert_eq!(from_bytes::<f32>(&to_bytes(&v)), v);
    }
}
