//! Halo exchange of a [`GpuFluid`] between ranks: the outgoing columns are packed on the
//! device, sent through the host, and staged on the device for the unpack kernel.

use super::*;

impl<T: Real> GpuFluid<T> {
    /// Whether this rank exchanges halos with a neighbour.
    pub(super) fn has_peers(&self) -> bool {
        self.geo.peers != 0
    }

    /// Extract the outgoing halo columns of the current buffer and exchange them with the
    /// neighbours; the received columns are staged in `aux`, ready for `unpack_halo`.
    /// `overlap` is recorded and submitted before the transfer, so it runs on the device
    /// while the messages travel. Returns the exposed wait (s). Collective.
    pub(super) fn exchange(
        &mut self,
        comm: &dyn Comm,
        overlap: Option<wgpu::CommandEncoder>,
    ) -> f64 {
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
        // The staged values are already the little-endian bytes the halo buffers hold.
        let side_bytes = HALO_DIRS * rows * T::BYTES;
        let at = self.geo.halo_at as usize * T::BYTES;
        let mut out = std::mem::take(&mut self.read_bytes);
        self.download_into(&self.aux_buf, at, 2 * side_bytes, &mut out);
        for (s, side) in [Side::Left, Side::Right].into_iter().enumerate() {
            if self.host.halo.peer(side).is_some() {
                let part = &out[s * side_bytes..(s + 1) * side_bytes];
                self.host.halo.send_mut(side).copy_from_slice(part);
            }
        }
        self.read_bytes = out;
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
    pub(super) fn refresh_exchange(&mut self, comm: &dyn Comm) {
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
}
