//! The QEMU board models the micro:bit v2 where the demo measures what the v2
//! runs: the same accelerometer link (`board::accel_link`) and the same maze
//! reach and ghost sizes (`board::game_sizes`), both shared, never imported
//! from the v2's module; its constants must stay the v2's so that QEMU's stack
//! and flash figures are the v2's.

use marble_rolling::board::{accel_link, microbit, qemu};

#[test]
fn the_qemu_board_keeps_the_v2s_maze_and_ghost_sizes() {
    assert_eq!(qemu::MAZE_REACH, microbit::MAZE_REACH);
    assert_eq!(qemu::GHOST_BYTES, microbit::GHOST_BYTES);
    assert_eq!(
        qemu::GHOSTS_BYTES as u32,
        microbit::GHOSTS.end - microbit::GHOSTS.start
    );
}

#[test]
fn the_qemu_board_polls_its_chip_as_the_v2_does() {
    assert_eq!(qemu::SENSOR_AXIS_MAP, accel_link::AXIS_MAP);
    assert_eq!(qemu::SENSOR_AXIS_MAP, microbit::AXIS_MAP);
    assert_eq!(qemu::INPUT_PERIOD_MS, microbit::INPUT_PERIOD_MS);
    assert_eq!(qemu::SUPERVISOR, microbit::SUPERVISOR);
    assert_eq!(qemu::TRANSFER_TIMEOUT_MS, microbit::I2C_TIMEOUT_MS);
    assert_eq!(qemu::DEFAULT_COPY_BUFFER, microbit::TWIM_COPY_BUFFER_BYTES);
}
