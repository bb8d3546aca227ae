//! Material points, structure of arrays: one array per physical quantity, index-aligned.
//! Vector and tensor quantities are stored as small fixed arrays per point (`[f64; 2]`,
//! `[f64; 4]`), so a sweep reads each field as one contiguous stream and no point owns a
//! heap object.

use decomposition::PackRows;

/// The material points of one rank.
#[derive(Debug, Clone, Default)]
pub struct Points {
    /// Stable identity, unique over all ranks; the canonical order within a cell.
    pub id: Vec<u64>,
    /// Position (m).
    pub pos: Vec<[f64; 2]>,
    /// Velocity (m/s).
    pub vel: Vec<[f64; 2]>,
    /// APIC affine moment B = Σ_I S v_I (x_I − x_p)ᵀ = [Bxx, Bxy, Byx, Byy] (m²/s; Jiang et
    /// al. 2015): the point's velocity field is v_p + B D⁻¹ (x − x_p), D = Σ_I S (x_I −
    /// x_p)(x_I − x_p)ᵀ (see [`super::transfer::inertia_1d`]). Zero without APIC.
    pub affine: Vec<[f64; 4]>,
    /// Mass per metre of depth (kg/m).
    pub mass: Vec<f64>,
    /// Initial volume per metre of depth (m²); the current volume is `vol0 · det F`.
    pub vol0: Vec<f64>,
    /// Initial half-length of the point's domain (m), h / (2 n) for n×n points per cell.
    pub half0: Vec<f64>,
    /// Cauchy stress [σxx, σyy, σxy, σzz] (Pa, tension positive, plane strain).
    pub stress: Vec<[f64; 4]>,
    /// Accumulated small-strain measure [εxx, εyy, εxy] (tensor shear), sum of increments.
    pub strain: Vec<[f64; 3]>,
    /// Deformation gradient [Fxx, Fxy, Fyx, Fyy].
    pub defgrad: Vec<[f64; 4]>,
    /// Equivalent plastic strain (Mohr–Coulomb state variable; 0 for elastic points).
    pub eps_p: Vec<f64>,
    /// Index of the point's material in the scene's material list.
    pub material: Vec<u16>,
}

impl Points {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.id.len()
    }

    /// True when there are no points.
    pub fn is_empty(&self) -> bool {
        self.id.is_empty()
    }

    /// Add a point at rest, unstressed and undeformed. `vol` (m²) is its area per metre
    /// of depth, `density` (kg/m³) its material density, `half` (m) its half-length.
    #[allow(clippy::too_many_arguments)]
    pub fn push(
        &mut self,
        id: u64,
        pos: [f64; 2],
        vol: f64,
        density: f64,
        half: f64,
        material: u16,
    ) {
        self.id.push(id);
        self.pos.push(pos);
        self.vel.push([0.0; 2]);
        self.affine.push([0.0; 4]);
        self.mass.push(density * vol);
        self.vol0.push(vol);
        self.half0.push(half);
        self.stress.push([0.0; 4]);
        self.strain.push([0.0; 3]);
        self.defgrad.push([1.0, 0.0, 0.0, 1.0]);
        self.eps_p.push(0.0);
        self.material.push(material);
    }

    /// Current volume per metre of depth (m²) of point `i`: V₀ det F.
    pub fn volume(&self, i: usize) -> f64 {
        let f = self.defgrad[i];
        self.vol0[i] * (f[0] * f[3] - f[1] * f[2])
    }

    /// Keep only the points with `keep[i]`, preserving their order.
    pub fn retain(&mut self, keep: &[bool]) {
        fn filter<T: Copy>(v: &mut Vec<T>, keep: &[bool]) {
            let mut k = keep.iter();
            v.retain(|_| *k.next().unwrap_or(&false));
        }
        filter(&mut self.id, keep);
        filter(&mut self.pos, keep);
        filter(&mut self.vel, keep);
        filter(&mut self.affine, keep);
        filter(&mut self.mass, keep);
        filter(&mut self.vol0, keep);
        filter(&mut self.half0, keep);
        filter(&mut self.stress, keep);
        filter(&mut self.strain, keep);
        filter(&mut self.defgrad, keep);
        filter(&mut self.eps_p, keep);
        filter(&mut self.material, keep);
    }

    /// Reorder every array so that new index `k` holds old index `order[k]`. `scratch` is
    /// reused between calls so that a steady-state permutation allocates nothing.
    pub fn permute(&mut self, order: &[u32], scratch: &mut PermuteScratch) {
        use rayon::prelude::*;
        fn apply<T: Copy + Send + Sync>(v: &mut Vec<T>, order: &[u32], tmp: &mut Vec<T>) {
            tmp.clear();
            tmp.par_extend(order.par_iter().map(|&o| v[o as usize]));
            std::mem::swap(v, tmp);
        }
        apply(&mut self.id, order, &mut scratch.u64s);
        apply(&mut self.pos, order, &mut scratch.v2);
        apply(&mut self.vel, order, &mut scratch.v2);
        apply(&mut self.affine, order, &mut scratch.v4);
        apply(&mut self.mass, order, &mut scratch.f64s);
        apply(&mut self.vol0, order, &mut scratch.f64s);
        apply(&mut self.half0, order, &mut scratch.f64s);
        apply(&mut self.stress, order, &mut scratch.v4);
        apply(&mut self.strain, order, &mut scratch.v3);
        apply(&mut self.defgrad, order, &mut scratch.v4);
        apply(&mut self.eps_p, order, &mut scratch.f64s);
        apply(&mut self.material, order, &mut scratch.u16s);
    }

    /// Total mass (kg/m), summed in storage order.
    pub fn total_mass(&self) -> f64 {
        self.mass.iter().sum()
    }
}

/// Reusable buffers for [`Points::permute`].
#[derive(Debug, Default)]
pub struct PermuteScratch {
    u64s: Vec<u64>,
    u16s: Vec<u16>,
    f64s: Vec<f64>,
    v2: Vec<[f64; 2]>,
    v3: Vec<[f64; 3]>,
    v4: Vec<[f64; 4]>,
}

/// A point travels (migration, checkpoints) as its full state: ids and material as exact
/// integer bit patterns.
impl PackRows for Points {
    const WORDS: usize = 25;

    fn pack_row(&self, i: usize, out: &mut Vec<f64>) {
        out.push(f64::from_bits(self.id[i]));
        out.extend_from_slice(&self.pos[i]);
        out.extend_from_slice(&self.vel[i]);
        out.extend_from_slice(&self.affine[i]);
        out.extend_from_slice(&[self.mass[i], self.vol0[i], self.half0[i]]);
        out.extend_from_slice(&self.stress[i]);
        out.extend_from_slice(&self.strain[i]);
        out.extend_from_slice(&self.defgrad[i]);
        out.push(self.eps_p[i]);
        out.push(f64::from_bits(self.material[i] as u64));
    }

    fn push_row(&mut self, p: &[f64]) {
        assert_eq!(p.len(), Self::WORDS, "packed point has {} words", p.len());
        self.id.push(p[0].to_bits());
        self.pos.push([p[1], p[2]]);
        self.vel.push([p[3], p[4]]);
        self.affine.push([p[5], p[6], p[7], p[8]]);
        self.mass.push(p[9]);
        self.vol0.push(p[10]);
        self.half0.push(p[11]);
        self.stress.push([p[12], p[13], p[14], p[15]]);
        self.strain.push([p[16], p[17], p[18]]);
        self.defgrad.push([p[19], p[20], p[21], p[22]]);
        self.eps_p.push(p[23]);
        self.material.push(p[24].to_bits() as u16);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pack_round_trip_and_permute() {
        let mut p = Points::default();
        for i in 0..5u64 {
            p.push(
                10 + i,
                [i as f64, 2.0 * i as f64],
                0.5,
                2000.0,
                0.1,
                i as u16,
            );
            p.stress[i as usize] = [i as f64, -1.0, 0.5, 3.0];
            p.affine[i as usize] = [0.5, i as f64, -2.0, 1.0];
        }
        let mut buf = Vec::new();
        p.pack_row(3, &mut buf);
        assert_eq!(buf.len(), Points::WORDS);
        let mut q = Points::default();
        q.push_row(&buf);
        assert_eq!(q.id[0], 13);
        assert_eq!(q.stress[0], p.stress[3]);
        assert_eq!(q.affine[0], p.affine[3]);
        assert_eq!(q.defgrad[0], p.defgrad[3]);
        assert_eq!(q.material[0], 3);
        let mut s = PermuteScratch::default();
        p.permute(&[4, 3, 2, 1, 0], &mut s);
        assert_eq!(p.id, vec![14, 13, 12, 11, 10]);
        assert_eq!(p.pos[0], [4.0, 8.0]);
        p.retain(&[true, false, true, false, true]);
        assert_eq!(p.id, vec![14, 12, 10]);
        assert!((p.volume(0) - 0.5).abs() < 1e-15);
    }
}
