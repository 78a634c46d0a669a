//! micro:bit v2 accelerometer axis mapping: one test per orientation.
//!
//! Raw readings are what the LSM303AGR reports in each pose under the
//! assumption documented on `board::microbit::AXIS_MAP` (raw x = +1 g with
//! the right edge down, raw y = +1 g with the logo edge down, raw z = +1 g
//! lying screen-down). Expected values are the board frame: x right, y up
//! out of the LEDs, z towards the player (edge connector side).

use marble_rolling::board::microbit::AXIS_MAP;
use marble_rolling::input::sensor::{AccelMg, AxisMap};

fn board(raw: (i32, i32, i32)) -> AccelMg {
    AXIS_MAP.apply(AccelMg::new(raw.0, raw.1, raw.2))
}

#[test]
fn table_is_a_signed_permutation() {
    assert!(AXIS_MAP.is_permutation());
}

#[test]
fn flat_screen_up_reads_plus_one_g_on_y() {
    assert_eq!(board((0, 0, -1000)), AccelMg::new(0, 1000, 0));
    assert_eq!(board((0, 0, -1000)), AccelMg::LEVEL);
}

#[test]
fn face_down_reads_minus_one_g_on_y() {
    assert_eq!(board((0, 0, 1000)), AccelMg::new(0, -1000, 0));
}

#[test]
fn right_edge_down_gives_negative_x() {
    // Marble rolls towards +x (right): x < 0.
    assert_eq!(board((1000, 0, 0)), AccelMg::new(-1000, 0, 0));
}

#[test]
fn left_edge_down_gives_positive_x() {
    assert_eq!(board((-1000, 0, 0)), AccelMg::new(1000, 0, 0));
}

#[test]
fn near_edge_down_gives_negative_z() {
    // Edge connector (towards the player) down, logo up: the marble rolls
    // towards the player (+z), so z < 0, like x for the right edge.
    assert_eq!(board((0, -1000, 0)), AccelMg::new(0, 0, -1000));
}

#[test]
fn far_edge_down_gives_positive_z() {
    // Logo edge (away from the player) down.
    assert_eq!(board((0, 1000, 0)), AccelMg::new(0, 0, 1000));
}

#[test]
fn small_right_tilt_keeps_y_up() {
    // 10° right edge down from flat: raw x = +174, raw z = -985.
    let b = board((174, 0, -985));
    assert_eq!(b, AccelMg::new(-174, 985, 0));
}

#[test]
fn mapping_preserves_magnitude_and_saturates() {
    let raw = AccelMg::new(300, -400, 1200);
    assert_eq!(board((300, -400, 1200)).magnitude_sq(), raw.magnitude_sq());
    // i32::MIN negated saturates instead of overflowing.
    assert_eq!(board((i32::MIN, 0, 0)).x, i32::MAX);
}

#[test]
fn identity_is_identity() {
    let s = AccelMg::new(1, 2, 3);
    assert_eq!(AxisMap::IDENTITY.apply(s), s);
}
