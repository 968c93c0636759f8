//! The motor current in the monitor's rows: what each series' block holds
//! and what a count of `present_current` is in milliamps.
//!
//! | series  | block read           | `present_current` (69)            | row's `current_ma` |
//! |---------|----------------------|-----------------------------------|--------------------|
//! | STS/SMS | 40 ..= 70 (31 bytes) | sign bit 15, the map's `6.5 mA`   | counts x 6.5 mA    |
//! | SCS     | 40 ..= 66 (27 bytes) | not documented, no unit           | `None` (`-`)       |
//!
//! The step comes from the register map's unit (`6.5 mA` in the STS/SMS
//! table, which the control-tables reference gives for the STS3215), so
//! the protocol crate stays the one place that states it. A register
//! whose unit is not in mA (the SCS table's, which states none) gives no
//! current rather than a figure of unknown scale.

use servobus_protocol::registers::{addr, sts, Register, Series};

/// Bytes of the block a series' servos are read with every refresh: torque
/// enable (40) to the moving flag (66) on SCS servos, on to the end of the
/// present current (69, 70) on STS/SMS servos.
pub const fn block_len(series: Series) -> u8 {
    match series {
        // 71 - 40: the end is a u8 address plus 2, well within a u8 here.
        Series::Sts => (sts::PRESENT_CURRENT.register().end() - addr::TORQUE_ENABLE as u16) as u8,
        Series::Scs => super::BLOCK_LEN,
    }
}

/// Milliamps per count of `reg` when its unit is a current in mA (`6.5 mA`:
/// 6.5, `mA`: 1); `None` for any other unit or none.
pub fn milliamps_per_count(reg: &Register) -> Option<f64> {
    let unit = reg.unit.trim();
    let step = match unit.strip_suffix("mA")?.trim() {
        "" => 1.0,
        step => step.parse::<f64>().ok()?,
    };
    (step.is_finite() && step > 0.0).then_some(step)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sts_blocks_reach_the_current_and_scs_blocks_stop_at_moving() {
        assert_eq!(block_len(Series::Sts), 31);
        assert_eq!(block_len(Series::Scs), 27);
    }

    #[test]
    fn the_sts_current_counts_in_6_5_ma_and_the_scs_one_in_nothing_known() {
        let sts = Series::Sts.map().get("present_current");
        assert_eq!(sts.and_then(milliamps_per_count), Some(6.5));
        let scs = Series::Scs.map().get("present_current");
        assert_eq!(scs.and_then(milliamps_per_count), None);
        let load = Series::Sts.map().get("present_load");
        assert_eq!(load.and_then(milliamps_per_count), None);
    }
}
