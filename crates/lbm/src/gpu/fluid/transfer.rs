//! Host–device transfers of a [`GpuFluid`]: populations up and down (as the device stores
//! them, f16 or the lattice's precision), and reads of any buffer through the read-back
//! buffer.

use super::*;

/// `values` as little-endian bytes.
pub(in crate::gpu) fn to_bytes<T: Real>(values: &[T]) -> Vec<u8> {
    let mut out = vec![0u8; values.len() * T::BYTES];
    decomposition::pack_words(&mut out, values.iter().copied());
    out
}

/// Little-endian `bytes` as values (`T::BYTES` each).
pub(in crate::gpu) fn from_bytes<T: Real>(bytes: &[u8]) -> Vec<T> {
    let mut out = Vec::with_capacity(bytes.len() / T::BYTES);
    extend_from_bytes(bytes, &mut out);
    out
}

/// Append little-endian `bytes` to `out` as values (`T::BYTES` each).
pub(in crate::gpu) fn extend_from_bytes<T: Real>(bytes: &[u8], out: &mut Vec<T>) {
    out.extend(decomposition::unpack_words::<T>(bytes));
}

impl<T: Real> GpuFluid<T> {
    /// Copy both host population buffers to the device (start and restart).
    pub(super) fn upload(&mut self) {
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

    /// Copy device buffer `b` to the host's buffer `b`.
    pub(super) fn pull(&mut self, b: usize) {
        self.flush();
        let per = self.split.planes_per_part() * self.host.plane;
        for j in 0..self.split.parts {
            let bytes = per * if self.f16 { 2 } else { T::BYTES };
            let v = self.pops_from_bytes(&self.download(&self.pops[b][j], 0, bytes));
            self.host.buf[b][j * per..(j + 1) * per].copy_from_slice(&v);
        }
    }

    /// Populations as the device stores them.
    pub(super) fn pops_to_bytes(&self, values: &[T]) -> Vec<u8> {
        if !self.f16 {
            return to_bytes(values);
        }
        values
            .iter()
            .flat_map(|v| half::f16::from_f64(v.to_f64()).to_le_bytes())
            .collect()
    }

    /// Inverse of [`GpuFluid::pops_to_bytes`].
    pub(super) fn pops_from_bytes(&self, bytes: &[u8]) -> Vec<T> {
        if !self.f16 {
            return from_bytes(bytes);
        }
        bytes
            .chunks_exact(2)
            .map(|b| T::from_f64(half::f16::from_le_bytes([b[0], b[1]]).to_f64()))
            .collect()
    }

    /// Read `bytes` bytes of `buffer` from `offset`, through the read-back buffer in chunks.
    pub(in crate::gpu) fn download(
        &self,
        buffer: &wgpu::Buffer,
        offset: usize,
        bytes: usize,
    ) -> Vec<u8> {
        let mut out = Vec::with_capacity(bytes);
        self.download_into(buffer, offset, bytes, &mut out);
        out
    }

    /// As [`Self::download`], into `out` (cleared first; its allocation is kept, so a
    /// download every step allocates nothing once `out` has grown).
    pub(in crate::gpu) fn download_into(
        &self,
        buffer: &wgpu::Buffer,
        offset: usize,
        bytes: usize,
        out: &mut Vec<u8>,
    ) {
        out.clear();
        let chunk = self.readback.size() as usize;
        let mut at = 0;
        while at < bytes {
            let n = (bytes - at).min(chunk);
            let n4 = n.div_ceil(4) * 4;
            let mut enc = self.ctx.device.create_command_encoder(&Default::default());
            enc.copy_buffer_to_buffer(buffer, (offset + at) as u64, &self.readback, 0, n4 as u64);
            self.ctx.queue.submit([enc.finish()]);
            // The copy is whole words: read them, keep the n bytes asked for.
            self.ctx
                .read_append(&self.readback, n4 as u64, out)
                .unwrap_or_else(|e| panic!("{e}: the GPU device was lost"));
            out.truncate(at + n);
            at += n;
        }
    }

    /// `count` reals of the auxiliary buffer from `first`.
    pub(super) fn aux_values(&self, first: usize, count: usize) -> Vec<T> {
        from_bytes(&self.download(&self.aux_buf, first * T::BYTES, count * T::BYTES))
    }
}
