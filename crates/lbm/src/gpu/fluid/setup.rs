//! Building a [`GpuFluid`]: device buffers, geometry, cell lists, parameters, bind
//! groups and pipelines.

use super::*;

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
        assert_eq!(
            host.buffers(),
            2,
            "the device takes a two-buffer lattice (Lattice::new_slab, not in place)"
        );
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
        let (geom, words) = geometry_words(&host);
        let (inner, edge, rest_force) = cell_lists(&host);
        let nslots = host.forces.row_start[ny];
        let ns = host.solids.len();
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
        let lattice_layout = lattice_layout(dev, split);
        let list_layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("cell list"),
            entries: &[storage(0, true)],
        });
        let uniforms = [&geo_buf, &prm_buf, &geom_buf, &aux_buf, &bad_buf];
        let groups = lattice_groups(dev, &lattice_layout, uniforms, &pops, split);
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
            lattice_layout,
            groups,
            inner,
            edge,
            probes: None,
            pipes,
            nslots,
            rest_force,
            pending: None,
            pending_steps: 0,
            moving: None,
            moving_idx: Vec::new(),
            moving_real: Vec::new(),
            read_bytes: Vec::new(),
            read_values: Vec::new(),
        };
        gpu.upload();
        Ok(gpu)
    }

    /// Real parameters (`prm` in shaders/common.wgsl): collision, force, inlet, pressures, solid
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

    /// The pipeline-overridable constants that select the collision (common.wgsl).
    pub(super) fn constants_of(host: &Lattice<T>) -> [(&'static str, f64); 3] {
        let family = match host.collision {
            Collision::Bgk => 0.0,
            Collision::Trt { .. } => 1.0,
            Collision::Mrt { .. } => 2.0,
        };
        let forced = host.params.force[0] != T::default() || host.params.force[1] != T::default();
        [
            ("FAMILY", family),
            ("SMAG", host.smagorinsky as u8 as f64),
            ("FORCED", forced as u8 as f64),
        ]
    }

    /// [`GpuFluid::constants_of`] this lattice.
    pub(in crate::gpu) fn pipeline_constants(&self) -> [(&'static str, f64); 3] {
        Self::constants_of(&self.host)
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
            label: Some("grainflow lbm"),
            source: wgpu::ShaderSource::Wgsl(
                shader_source(T::NAME, if f16 { "f16" } else { T::NAME }, split).into(),
            ),
        });
        let layout = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("lbm"),
            bind_group_layouts: &[Some(lattice), Some(list)],
            immediate_size: 0,
        });
        let constants = Self::constants_of(host);
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
}

/// The device's geometry words of `host`: one bit per padded cell that the CPU runs as
/// bulk (plain cells), then each padded cell's type; and where the types start.
fn geometry_words<T: Real>(host: &Lattice<T>) -> (Vec<u32>, usize) {
    let (stride, plane) = (host.stride, host.plane);
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
    (geom, words)
}

/// The special and edge cell lists of `host` (padded cell, force slot; the first entry
/// holds the count), and each force slot's rest-state term per solid: −2 w_i c_i for each
/// of its links into that solid.
#[allow(clippy::type_complexity)]
fn cell_lists<T: Real>(host: &Lattice<T>) -> (Vec<[u32; 2]>, Vec<[u32; 2]>, Vec<[f64; 2]>) {
    let (ny, stride) = (host.ny, host.stride);
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
                let n = (k as isize - CX[i] as isize - CY[i] as isize * stride as isize) as usize;
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
    (inner, edge, rest_force)
}

/// The layout of the lattice group: the uniforms, parameters, geometry, aux and
/// instability buffers, then each part's source and destination populations.
fn lattice_layout(dev: &wgpu::Device, split: Split) -> wgpu::BindGroupLayout {
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
    dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("lattice"),
        entries: &entries,
    })
}

/// The two lattice groups (reading buffer c, writing buffer 1 − c), binding `uniforms`
/// (geo, parameters, geometry, aux, instability) and the populations `pops`.
fn lattice_groups(
    dev: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    uniforms: [&wgpu::Buffer; 5],
    pops: &[Vec<wgpu::Buffer>; 2],
    split: Split,
) -> [wgpu::BindGroup; 2] {
    std::array::from_fn(|c| {
        let mut e: Vec<wgpu::BindGroupEntry> = uniforms
            .iter()
            .enumerate()
            .map(|(b, buf)| wgpu::BindGroupEntry {
                binding: b as u32,
                resource: buf.as_entire_binding(),
            })
            .collect();
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
            layout,
            entries: &e,
        })
    })
}
