//! Moving surfaces (`lbm::moving`) on the device backend: the plan's cells are recomputed on
//! the device right after the sweep (`shaders/moving.wgsl`), and their momenta summed per
//! body and column there (`shaders/body_columns.wgsl`) in the order the host's collect uses
//! (so the forces have the same bits on any rank count): what comes back is about a dozen
//! loads per body, or one momentum per link or solid share when the caller asks for no
//! sums. Rest fills, refills and cell momenta move whole cells between host and device
//! (`cells.rs`).

use super::super::body_columns::{append_bodies, read_sums};
use super::super::buffers::{job_groups, round16, shader_source};
use super::{extend_from_bytes, from_bytes, to_bytes, GpuFluid};
use crate::moving::PsmPlan;
use crate::moving::{BodyColumns, MovingCells, RigidMotion};
use crate::Real;
use rayon::prelude::*;

/// Pipelines and buffers of the moving-surface kernels (made on first use).
pub(crate) struct MovingDevice {
    links: wgpu::ComputePipeline,
    psm: wgpu::ComputePipeline,
    body_links: wgpu::ComputePipeline,
    body_psm: wgpu::ComputePipeline,
    gather: wgpu::ComputePipeline,
    scatter: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    /// (index buffer, real buffer, their bind group), grown on demand.
    buffers: Option<(wgpu::Buffer, wgpu::Buffer, wgpu::BindGroup)>,
}

/// Which moving kernel to run.
#[derive(Clone, Copy)]
pub(in crate::gpu) enum Kernel {
    Links,
    Psm,
    BodyLinks,
    BodyPsm,
    Gather,
    Scatter,
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

impl<T: Real> GpuFluid<T> {
    /// The moving-surface kernels, compiled on first use.
    fn moving_device(&mut self) -> &mut MovingDevice {
        if self.moving.is_none() {
            let dev = &self.ctx.device;
            let layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("moving surfaces"),
                entries: &[storage(0, true), storage(1, false)],
            });
            let source = shader_source(T::NAME, self.stored_name(), self.split)
                + include_str!("../shaders/moving.wgsl")
                + include_str!("../shaders/body_columns.wgsl");
            let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("grainflow moving surfaces"),
                source: wgpu::ShaderSource::Wgsl(source.into()),
            });
            let pl = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("moving surfaces"),
                bind_group_layouts: &[
                    Some(&self.lattice_layout),
                    Some(&self.list_layout),
                    Some(&layout),
                ],
                immediate_size: 0,
            });
            let constants = self.pipeline_constants();
            let make = |entry: &str| {
                dev.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(entry),
                    layout: Some(&pl),
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants: &constants,
                        zero_initialize_workgroup_memory: false,
                    },
                    cache: None,
                })
            };
            self.moving = Some(MovingDevice {
                links: make("moving_links"),
                psm: make("moving_psm"),
                body_links: make("body_columns_links"),
                body_psm: make("body_columns_psm"),
                gather: make("gather_cells"),
                scatter: make("scatter_cells"),
                layout,
                buffers: None,
            });
        }
        self.moving.as_mut().expect("made above")
    }

    /// Run `kernels` in turn, each over its number of items, with the index data `idx` and
    /// real data `real` (uploaded first; the real buffer holds `scratch` more reals that
    /// the kernels write), the lattice bound as group `g`; submitted at once. Read the
    /// results back from the real buffer ([`GpuFluid::moving_real_buffer`]).
    pub(in crate::gpu) fn run_moving(
        &mut self,
        kernels: &[(Kernel, usize)],
        g: usize,
        idx: &[u32],
        real: &[T],
        scratch: usize,
    ) {
        self.flush();
        let ctx = self.ctx.clone();
        let (idx_bytes, real_bytes) = (
            round16(idx.len() * 4),
            round16((real.len() + scratch) * T::BYTES),
        );
        self.moving_device();
        let (lattice_group, list_group) = (self.groups[g].clone(), self.inner_list_group());
        let dev = self.moving.as_mut().expect("made above");
        let grow = dev
            .buffers
            .as_ref()
            .is_none_or(|(i, r, _)| i.size() < idx_bytes || r.size() < real_bytes);
        if grow {
            let make = |label: &str, bytes: u64| {
                ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    // Room to grow without a new buffer every step.
                    size: bytes + bytes / 4,
                    usage: wgpu::BufferUsages::STORAGE
                        | wgpu::BufferUsages::COPY_DST
                        | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                })
            };
            let (i, r) = (
                make("moving index", idx_bytes),
                make("moving real", real_bytes),
            );
            let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("moving surfaces"),
                layout: &dev.layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: i.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: r.as_entire_binding(),
                    },
                ],
            });
            dev.buffers = Some((i, r, group));
        }
        let (ibuf, rbuf, group) = dev.buffers.as_ref().expect("made above");
        ctx.queue.write_buffer(ibuf, 0, bytemuck::cast_slice(idx));
        if !real.is_empty() {
            ctx.queue.write_buffer(rbuf, 0, &to_bytes(real));
        }
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        for &(kernel, threads) in kernels.iter().filter(|k| k.1 > 0) {
            let pipe = match kernel {
                Kernel::Links => &dev.links,
                Kernel::Psm => &dev.psm,
                Kernel::BodyLinks => &dev.body_links,
                Kernel::BodyPsm => &dev.body_psm,
                Kernel::Gather => &dev.gather,
                Kernel::Scatter => &dev.scatter,
            };
            // One pass per kernel: the next sees all the writes of the one before.
            let (gx, gy) = job_groups(threads);
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(pipe);
            pass.set_bind_group(0, &lattice_group, &[]);
            pass.set_bind_group(1, &list_group, &[]);
            pass.set_bind_group(2, group, &[]);
            pass.dispatch_workgroups(gx, gy, 1);
        }
        ctx.queue.submit([enc.finish()]);
    }

    /// The real buffer of the last moving kernel.
    fn moving_real_buffer(&self) -> &wgpu::Buffer {
        &self
            .moving
            .as_ref()
            .and_then(|m| m.buffers.as_ref())
            .expect("a moving kernel ran")
            .1
    }

    /// `count` reals of the moving real buffer from `first`.
    pub(in crate::gpu) fn moving_reals(&self, first: usize, count: usize) -> Vec<T> {
        let bytes = self.download(
            self.moving_real_buffer(),
            first * T::BYTES,
            count * T::BYTES,
        );
        from_bytes(&bytes)
    }

    /// `count` reals of the moving real buffer from `first`, into `values` (cleared first),
    /// and the first bad plan cell of the kernel that wrote them (resetting the flag): one
    /// read-back, so one wait for the device per step, through buffers kept between steps.
    fn moving_reals_and_bad(
        &mut self,
        first: usize,
        count: usize,
        values: &mut Vec<T>,
    ) -> Option<usize> {
        let rbuf = self.moving_real_buffer();
        let bytes = count * T::BYTES;
        let at = bytes.div_ceil(4) * 4;
        values.clear();
        let flag = if at + 4 <= self.readback.size() as usize {
            let mut enc = self.ctx.device.create_command_encoder(&Default::default());
            if at > 0 {
                enc.copy_buffer_to_buffer(
                    rbuf,
                    (first * T::BYTES) as u64,
                    &self.readback,
                    0,
                    at as u64,
                );
            }
            enc.copy_buffer_to_buffer(&self.bad_buf, 12, &self.readback, at as u64, 4);
            self.ctx.queue.submit([enc.finish()]);
            let mut data = std::mem::take(&mut self.read_bytes);
            data.clear();
            self.ctx
                .read_append(&self.readback, (at + 4) as u64, &mut data)
                .unwrap_or_else(|e| panic!("{e}: the GPU device was lost"));
            let flag = u32::from_le_bytes(data[at..at + 4].try_into().expect("4 bytes"));
            extend_from_bytes(&data[..bytes], values);
            self.read_bytes = data;
            flag
        } else {
            let data = self.download(rbuf, first * T::BYTES, bytes);
            extend_from_bytes(&data, values);
            let v = self.download(&self.bad_buf, 12, 4);
            u32::from_le_bytes(v[0..4].try_into().expect("4 bytes"))
        };
        self.ctx
            .queue
            .write_buffer(&self.bad_buf, 12, bytemuck::bytes_of(&u32::MAX));
        (flag != u32::MAX).then_some(flag as usize)
    }

    /// Recompute the cells of `moving` right after the sweep (the lattice group whose source
    /// is the buffer the sweep read), and sum their momenta per body and column when its
    /// [`BodyColumns`] ask for it (then only those sums come back). Returns the plan index
    /// and density of the first cell that went bad. The upload is packed in parallel into
    /// buffers kept between steps.
    pub(crate) fn moving_cells(&mut self, moving: &mut MovingCells<'_>) -> Option<(usize, f64)> {
        let prev = self.host_mut().cur ^ 1;
        let (stride, ny) = (self.host_mut().stride, self.host_mut().ny);
        self.ctx
            .queue
            .write_buffer(&self.bad_buf, 12, bytemuck::bytes_of(&u32::MAX));
        let (mut idx, mut real) = (
            std::mem::take(&mut self.moving_idx),
            std::mem::take(&mut self.moving_real),
        );
        idx.clear();
        real.clear();
        let bad = match moving {
            MovingCells::None => None,
            MovingCells::Links(plan, mom, sums) => {
                let (n, l) = (plan.cells.len(), plan.links.len());
                idx.extend_from_slice(&[n as u32, l as u32]);
                idx.extend_from_slice(&plan.cells);
                idx.extend_from_slice(&plan.start);
                idx.par_extend(plan.links.par_iter().map(|k| k.bits()));
                let plan = &**plan;
                real.par_extend((0..l).into_par_iter().map(|j| T::from_f64(plan.q(j))));
                // Each link's wall term, cell by cell (a cell's links are contiguous).
                real.par_extend((0..n).into_par_iter().flat_map_iter(|c| {
                    let k = plan.cells[c] as usize;
                    let y = PsmPlan::row_of(stride, k);
                    (plan.start[c] as usize..plan.start[c + 1] as usize)
                        .map(move |j| T::from_f64(plan.wall(stride, k, y, plan.links[j])))
                }));
                assert_eq!(
                    real.len(),
                    2 * l,
                    "the plan's cells must hold all its links"
                );
                real.resize(3 * l, T::default());
                let frame = (&plan.rows[..], &plan.bodies[..], plan.x0, ny);
                let (values, bad) = self.run_plan(
                    (Kernel::Links, Kernel::BodyLinks, n),
                    prev,
                    (&mut idx, &mut real),
                    frame,
                    sums,
                    2 * l..3 * l,
                );
                mom.clear();
                mom.extend(values.iter().map(|v| v.to_f64()));
                bad.map(|c| (c, plan.cells[c]))
            }
            MovingCells::Partial(plan, mom, sums) => {
                let (n, s) = (plan.cells.len(), plan.shares.len());
                idx.extend_from_slice(&[n as u32, s as u32]);
                idx.extend_from_slice(&plan.cells);
                idx.extend_from_slice(&plan.start);
                if sums.wanted() {
                    // Each share's body, for the sums.
                    idx.par_extend(plan.shares.par_iter().map(|v| v.body));
                }
                let plan = &**plan;
                real.par_extend(plan.total.par_iter().map(|&b| T::from_f64(b)));
                real.par_extend(plan.shares.par_iter().map(|v| T::from_f64(v.b)));
                // The solids' velocities at the cell centres, share by share (x, then y).
                let velocity = |c: usize| {
                    let k = plan.cells[c] as usize;
                    let y = PsmPlan::row_of(stride, k);
                    (plan.start[c] as usize..plan.start[c + 1] as usize)
                        .map(move |j| plan.velocity(stride, k, y, plan.shares[j]))
                };
                for axis in 0..2 {
                    real.par_extend(
                        (0..n)
                            .into_par_iter()
                            .flat_map_iter(|c| velocity(c).map(move |u| T::from_f64(u[axis]))),
                    );
                }
                assert_eq!(
                    real.len(),
                    n + 3 * s,
                    "the plan's cells must hold all its shares"
                );
                real.resize(n + 5 * s, T::default());
                let frame = (&plan.rows[..], &plan.bodies[..], plan.x0, ny);
                let (values, bad) = self.run_plan(
                    (Kernel::Psm, Kernel::BodyPsm, n),
                    prev,
                    (&mut idx, &mut real),
                    frame,
                    sums,
                    n + 3 * s..n + 5 * s,
                );
                mom.clear();
                mom.extend(
                    values
                        .chunks_exact(2)
                        .map(|p| [p[0].to_f64(), p[1].to_f64()]),
                );
                bad.map(|c| (c, plan.cells[c]))
            }
        };
        (self.moving_idx, self.moving_real) = (idx, real);
        let (c, cell) = bad?;
        let h = self.gather(&[cell]);
        Some((c, 1.0 + h.iter().map(|v| v.to_f64()).sum::<f64>()))
    }

    /// Run a plan's moving kernel (`kernels`: it, the per-body kernel, the plan's cells)
    /// with the uploads `data`, the lattice group `g`. When `sums` ask for them, append the
    /// per-body section (`frame`: the plan's rows and bodies, its slab's global x of column
    /// 0, the rows), run the per-body kernel too and read only the sums back into `sums`;
    /// otherwise read back the momenta at `momenta` of the real buffer. Returns those
    /// momenta (none with sums) and the first bad plan cell.
    fn run_plan(
        &mut self,
        kernels: (Kernel, Kernel, usize),
        g: usize,
        data: (&mut Vec<u32>, &mut Vec<T>),
        frame: (&[u32], &[RigidMotion], i64, usize),
        sums: &mut BodyColumns,
        momenta: std::ops::Range<usize>,
    ) -> (Vec<T>, Option<usize>) {
        let (kernel, body, n) = kernels;
        let (idx, real) = data;
        let (rows, bodies, x0, ny) = frame;
        match append_bodies(idx, real, sums, rows, bodies, x0, ny) {
            Some(b) => {
                self.run_moving(&[(kernel, n), (body, b.groups)], g, idx, real, b.scratch);
                let mut values = std::mem::take(&mut self.read_values);
                let bad = self.moving_reals_and_bad(b.out_at, 4 * b.slots, &mut values);
                read_sums(&values, sums);
                self.read_values = values;
                (Vec::new(), bad)
            }
            None => {
                self.run_moving(&[(kernel, n)], g, idx, real, 0);
                let mut values = Vec::new();
                let bad = self.moving_reals_and_bad(momenta.start, momenta.len(), &mut values);
                (values, bad)
            }
        }
    }
}
