//! SYNC WRITE: one frame (or several, where the length byte would pass 255)
//! carrying a block for each servo, answered by nobody.

use servobus_protocol::{is_servo_id, EncodeError};
use servobus_timing::{servos_per_frame, sync_write_chunks, Block, PackError};

use crate::{Bus, BusError, Transport};

impl<T: Transport> Bus<T> {
    /// SYNC WRITE `data` at `address` to the servos `ids`: servo `ids[i]`
    /// gets `data[i * L..(i + 1) * L]` with `L = data.len() / ids.len()`.
    /// Nobody answers. The frames are cut and packed by
    /// [`servobus_timing::sync_write_chunks`] (split where the length byte
    /// would pass 255), the packer under
    /// [`servobus_timing::pack_sync_write`] that the cycle budget and the
    /// benches measure, each straight into the send buffer: nothing
    /// allocates, however many frames it takes.
    ///
    /// # Errors
    /// [`BusError::InvalidRequest`] when `data` is not `ids.len()` blocks of
    /// 1..=250 bytes; [`BusError::Encode`] for an invalid ID (nothing is
    /// sent, even when the ID would be in a later frame);
    /// [`BusError::Transport`].
    pub fn sync_write(&mut self, address: u8, ids: &[u8], data: &[u8]) -> Result<(), BusError> {
        if ids.is_empty() || data.is_empty() || !data.len().is_multiple_of(ids.len()) {
            return Err(BusError::InvalidRequest(
                "SYNC WRITE data must be one equal block per servo",
            ));
        }
        let len = u8::try_from(data.len() / ids.len())
            .map_err(|_| BusError::InvalidRequest("SYNC WRITE block too long"))?;
        let block = Block::new(address, len);
        let frames = sync_write_chunks(block, ids, data).map_err(pack_error)?;
        // Packing checks each frame's IDs as it goes; a request that spans
        // frames is checked whole first, so that it is never half sent.
        if ids.len() > servos_per_frame(len) {
            if let Some(&id) = ids.iter().find(|&&id| !is_servo_id(id)) {
                return Err(BusError::Encode(EncodeError::InvalidId {
                    id,
                    broadcast_allowed: false,
                }));
            }
        }
        for frame in frames {
            self.io.begin();
            self.io.tx_len = frame.pack(&mut self.io.tx).map_err(pack_error)?;
            self.count_sync_write(frame.ids);
            self.send()?;
        }
        Ok(())
    }

    /// Counts one SYNC WRITE frame to `ids`.
    fn count_sync_write(&mut self, ids: &[u8]) {
        self.counters.transactions += 1;
        for &id in ids {
            self.servos[usize::from(id)].transactions += 1;
        }
    }

    /// Sends a frame encoded by the caller (e.g. a SYNC WRITE packed by
    /// `servobus-timing`) and waits for no reply.
    ///
    /// # Errors
    /// [`BusError::InvalidRequest`] for a frame longer than any valid one;
    /// [`BusError::Transport`].
    pub fn send_frame(&mut self, frame: &[u8]) -> Result<(), BusError> {
        self.io.begin();
        let dst = self
            .io
            .tx
            .get_mut(..frame.len())
            .ok_or(BusError::InvalidRequest(
                "frame longer than any valid frame",
            ))?;
        dst.copy_from_slice(frame);
        self.io.tx_len = frame.len();
        self.counters.transactions += 1;
        self.send()?;
        Ok(())
    }
}

/// The bus error for a packing failure (the arguments were checked first,
/// and every frame fits the send buffer, so only an invalid ID or an
/// impossible block remains).
fn pack_error(e: PackError) -> BusError {
    match e {
        PackError::Encode(e) => BusError::Encode(e),
        _ => BusError::InvalidRequest("SYNC WRITE block too long"),
    }
}
