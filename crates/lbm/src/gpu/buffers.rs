//! Shader assembly (precision and population splitting) and small buffer helpers.

use super::context::{GpuContext, GpuError};

/// The kernels, without the prelude: bindings and helpers, collision, boundary links,
/// entry points (one WGSL module once concatenated).
const KERNELS: [&str; 4] = [
    include_str!("shaders/common.wgsl"),
    include_str!("shaders/collide.wgsl"),
    include_str!("shaders/boundaries.wgsl"),
    include_str!("shaders/kernels.wgsl"),
];

/// How the two population buffers are split over storage bindings: `parts` bindings per
/// buffer, `9 / parts` planes each.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Split {
    /// Bindings per population buffer: 1, 3 or 9.
    pub parts: usize,
}

impl Split {
    /// Planes per binding.
    pub fn planes_per_part(self) -> usize {
        9 / self.parts
    }

    /// Storage bindings a kernel needs (prm, geom, aux, bad, list, and two sets of parts).
    pub fn storage_bindings(self) -> u32 {
        5 + 2 * self.parts as u32
    }

    /// The fewest bindings whose parts fit `max_binding` bytes (and 2³² values), given
    /// `plane_bytes` per plane; `force` (from `GRAINFLOW_GPU_SPLIT`) overrides, for tests.
    pub fn choose(
        plane_values: usize,
        value_bytes: usize,
        ctx: &GpuContext,
    ) -> Result<Self, GpuError> {
        let max_binding = ctx
            .limits
            .max_storage_buffer_binding_size
            .min(ctx.limits.max_buffer_size);
        let fits = |parts: usize| {
            let values = (9 / parts) * plane_values;
            (values * value_bytes) as u64 <= max_binding && values <= u32::MAX as usize
        };
        let forced = std::env::var("GRAINFLOW_GPU_SPLIT")
            .ok()
            .and_then(|v| v.parse::<usize>().ok())
            .filter(|p| [1, 3, 9].contains(p));
        let parts = match forced {
            Some(p) => p,
            None => [1, 3, 9]
                .into_iter()
                .find(|&p| fits(p))
                .ok_or_else(|| GpuError::TooLarge {
                    adapter: ctx.adapter.name.clone(),
                    what: format!(
                        "one population plane is {} bytes, the largest storage binding {} bytes",
                        plane_values * value_bytes,
                        max_binding
                    ),
                })?,
        };
        let split = Split { parts };
        if split.storage_bindings() > ctx.limits.max_storage_buffers_per_shader_stage {
            return Err(GpuError::TooLarge {
                adapter: ctx.adapter.name.clone(),
                what: format!(
                    "{} storage bindings needed ({} population parts), {} allowed per stage",
                    split.storage_bindings(),
                    parts,
                    ctx.limits.max_storage_buffers_per_shader_stage
                ),
            });
        }
        Ok(split)
    }
}

/// Binding number of population part `j` of the source (current) buffer.
pub const SRC_BINDING: u32 = 10;
/// Binding number of population part `j` of the destination buffer.
pub const DST_BINDING: u32 = 20;

/// The WGSL source for precision `real` ("f32" or "f64") and `split`: a prelude with the
/// population bindings and their accessors, then the kernels.
/// `stored` is the population storage type ("f16" with `real` = "f32" for FP16 storage).
pub fn shader_source(real: &str, stored: &str, split: Split) -> String {
    let p = split.parts;
    let per = split.planes_per_part();
    let mut s = String::new();
    if stored == "f16" {
        s += "enable f16;\n";
    }
    s += &format!("alias real = {real};\nalias stored = {stored};\n");
    for j in 0..p {
        s += &format!(
            "@group(0) @binding({}) var<storage, read> src{j}: array<stored>;\n",
            SRC_BINDING as usize + j
        );
        s += &format!(
            "@group(0) @binding({}) var<storage, read_write> dst{j}: array<stored>;\n",
            DST_BINDING as usize + j
        );
    }
    let body = |name: &str, ret: bool| -> String {
        if p == 1 {
            return if ret {
                format!("return real({name}0[i * geo.plane + k]);")
            } else {
                format!("{name}0[i * geo.plane + k] = stored(v);")
            };
        }
        let mut b = format!("let j = (i % {per}u) * geo.plane + k;\nswitch (i / {per}u) {{\n");
        for part in 0..p {
            let label = if part + 1 == p {
                "default".to_string()
            } else {
                format!("case {part}u")
            };
            b += &if ret {
                format!("{label}: {{ return real({name}{part}[j]); }}\n")
            } else {
                format!("{label}: {{ {name}{part}[j] = stored(v); }}\n")
            };
        }
        b + "}"
    };
    s += &format!(
        "fn ld(i: u32, k: u32) -> real {{\n{}\n}}\n",
        body("src", true)
    );
    s += &format!(
        "fn ldd(i: u32, k: u32) -> real {{\n{}\n}}\n",
        body("dst", true)
    );
    s += &format!(
        "fn sto(i: u32, k: u32, v: real) {{\n{}\n}}\n",
        body("dst", false)
    );
    s + &KERNELS.concat()
}

/// Bytes rounded up to a multiple of 16 (copies need multiples of 4; 16 keeps vec4 alignment).
pub fn round16(bytes: usize) -> u64 {
    (bytes.div_ceil(16) * 16).max(16) as u64
}

/// Workgroups for a 1-D job of `n` items on 64-wide groups, folded into 2-D when one
/// dimension would exceed the 65 535 limit.
pub fn job_groups(n: usize) -> (u32, u32) {
    let groups = n.div_ceil(64).max(1);
    if groups <= 65_535 {
        (groups as u32, 1)
    } else {
        (65_535, groups.div_ceil(65_535) as u32)
    }
}

/// Workgroups for a per-cell sweep: 64 columns per group, rows strided over ≤ 65 535 groups.
pub fn cell_groups(nx: usize, ny: usize) -> (u32, u32) {
    (nx.div_ceil(64).max(1) as u32, ny.clamp(1, 65_535) as u32)
}
