//! [`GpuFluid`]: one rank's lattice on a wgpu device. The populations live on the device
//! for the whole run; only halos (every step, on several ranks), probes, forces, fields
//! and checkpoints cross to the host, when they are asked for.

use super::buffers::{
    cell_groups, job_groups, round16, shader_source, Split, DST_BINDING, SRC_BINDING,
};
use super::context::{GpuContext, GpuError};
use super::GpuStorage;
use crate::collision::Collision;
use crate::d2q9::{CX, CY, Q, W};
use crate::fields::Fields;
use crate::lattice::{FaceCondition, Lattice, StepError, FLUID, HALO_DIRS, MAX_SOLID};
use crate::moving::PlanKind;
use crate::{FluidBackend, Real};
use decomposition::{Comm, Side};
use std::sync::Arc;

mod halo;
pub(in crate::gpu) mod moving;
mod setup;
mod transfer;

pub(super) use transfer::{extend_from_bytes, from_bytes, to_bytes};

/// Uniform block of the kernels (`Geo` in shaders/common.wgsl).
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
    pub(super) ctx: Arc<GpuContext>,
    pub(super) split: Split,
    pops: [Vec<wgpu::Buffer>; 2],
    geo: Geo,
    prm_buf: wgpu::Buffer,
    aux_buf: wgpu::Buffer,
    pub(super) bad_buf: wgpu::Buffer,
    pub(super) readback: wgpu::Buffer,
    pub(super) list_layout: wgpu::BindGroupLayout,
    /// Layout of the lattice group (0).
    pub(super) lattice_layout: wgpu::BindGroupLayout,
    /// `groups[c]`: current buffer `c` as source, the other as destination.
    pub(super) groups: [wgpu::BindGroup; 2],
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
    /// Kernels of moving surfaces (grains), made on first use.
    pub(super) moving: Option<moving::MovingDevice>,
    /// The moving kernels' index upload of the last step (kept for its allocation).
    pub(super) moving_idx: Vec<u32>,
    /// The moving kernels' real upload of the last step (kept for its allocation).
    pub(super) moving_real: Vec<T>,
    /// The per-step read-backs' bytes (moving cells' sums, halos; kept for their
    /// allocation).
    pub(super) read_bytes: Vec<u8>,
    /// The per-step read-back's values (kept for their allocation).
    pub(super) read_values: Vec<T>,
    pending_steps: usize,
}

impl<T: Real> GpuFluid<T> {
    /// The host lattice (geometry; populations only after a pull).
    pub(crate) fn host_mut(&mut self) -> &mut Lattice<T> {
        &mut self.host
    }

    fn encoder(&self) -> wgpu::CommandEncoder {
        self.ctx.device.create_command_encoder(&Default::default())
    }

    /// The cell list of the inner special cells' bind group (a group 1 for kernels that
    /// do not read a list).
    pub(super) fn inner_list_group(&self) -> wgpu::BindGroup {
        self.inner.group.clone()
    }

    /// The WGSL type populations are stored in.
    pub(super) fn stored_name(&self) -> &'static str {
        if self.f16 {
            "f16"
        } else {
            T::NAME
        }
    }

    /// Submit the queued steps.
    pub(super) fn flush(&mut self) {
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
        if self.host.step.is_multiple_of(CHECK_EVERY) {
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
            // The device counts the steps done before the bad one; errors count from 1.
            step: all[0] as u64 + 1,
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

    fn refresh_halos(&mut self, comm: &dyn Comm) {
        self.flush();
        self.refresh_exchange(comm);
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
        self.pull(self.host.cur);
        self.host.export_interior()
    }

    fn stream_collide_moving(
        &mut self,
        comm: &dyn Comm,
        moving: &mut crate::moving::MovingCells<'_>,
    ) -> Result<Option<(usize, f64)>, StepError> {
        self.stream_collide(comm)?;
        Ok(self.moving_cells(moving))
    }

    fn sums_per_body(&self, _kind: PlanKind) -> bool {
        true
    }

    fn refresh_halos_full(&mut self, comm: &dyn Comm) {
        self.halos_full(comm)
    }

    fn set_rest(&mut self, cells: &[u32], velocity: &[[f64; 2]]) {
        self.rest(cells, velocity)
    }

    fn momentum_of_cells(&mut self, cells: &[u32], out: &mut Vec<[f64; 2]>) {
        self.cell_momenta(cells, out)
    }

    fn whole_cells(&mut self, cells: &[u32]) -> Vec<[f64; Q]> {
        self.gather(cells)
            .chunks_exact(Q)
            .map(|c| std::array::from_fn(|i| c[i].to_f64()))
            .collect()
    }

    fn apply_refills(&mut self, refills: &[crate::moving::Refill], momentum: &mut Vec<[f64; 2]>) {
        self.refills(refills, momentum)
    }

    fn import_interior(&mut self, data: &[T], step: u64, comm: &dyn Comm) {
        self.flush();
        self.host.import_interior(data, step, comm);
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
