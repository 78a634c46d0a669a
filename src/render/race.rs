//! A race on a matrix ([`crate::race`]): the chooser of channel and group,
//! the search for an opponent, the countdown, the maze with both marbles
//! (the opponent's replay drawn dimmer, at [`OPPONENT`]) and the verdict.
//! Pure functions of the race's state, so a board's race task, QEMU's race
//! board and the tests draw the same picture.

use super::{draw_ghost, Renderer, GHOST};
use crate::game::rules::Phase;
use crate::input::race_setup::RaceSetup;
use crate::matrix::{Brightness, Frame, MAX_BRIGHTNESS};
use crate::physics::Scalar;
use crate::race::{Race, Status, Verdict};

/// The opponent's marble: as dim as a ghost (it is one, of a run under way).
pub const OPPONENT: Brightness = GHOST;
/// Frames a second, the race's clock (the game's frame rate).
const SECOND: u32 = crate::game::rules::GameConfig::DEFAULT.frame_hz();

/// The won race: a tick.
const WON: [&[u8; 5]; 5] = [b".....", b"....#", b"...#.", b"#.#..", b".#..."];
/// The lost race: a cross.
const LOST: [&[u8; 5]; 5] = [b"#...#", b".#.#.", b"..#..", b".#.#.", b"#...#"];
/// A draw: two bars.
const DRAW: [&[u8; 5]; 5] = [b".....", b"#####", b".....", b"#####", b"....."];

/// A 5×5 picture centred on a `W`×`H` matrix (cut where it is smaller).
fn centred<const W: usize, const H: usize>(
    lit: impl Fn(usize, usize) -> bool,
    level: Brightness,
) -> Frame<W, H> {
    let (dx, dy) = (W.saturating_sub(5) / 2, H.saturating_sub(5) / 2);
    let mut frame = Frame::new();
    for y in 0..5.min(H) {
        for x in 0..5.min(W) {
            if lit(x, y) {
                frame.set(x + dx, y + dy, level);
            }
        }
    }
    frame
}

/// The chooser: its dots ([`RaceSetup::dots`]).
pub fn setup_frame<const W: usize, const H: usize>(setup: &RaceSetup) -> Frame<W, H> {
    let dots = setup.dots();
    centred(|x, y| dots[y][x], MAX_BRIGHTNESS)
}

/// Looking for an opponent, `now` frames in: a dot going round the edge of
/// the middle 5×5, a step each eighth of a second.
pub fn searching_frame<const W: usize, const H: usize>(now: u32) -> Frame<W, H> {
    // The 16 cells of a 5×5 square's edge, clockwise from the top left.
    let step = (now / (SECOND / 8).max(1) % 16) as usize;
    let (x, y) = match step {
        s @ 0..=3 => (s, 0),
        s @ 4..=7 => (4, s - 4),
        s @ 8..=11 => (12 - s, 4),
        s => (0, 16 - s),
    };
    centred(|cx, cy| (cx, cy) == (x, y), MAX_BRIGHTNESS)
}

/// The countdown with `left` frames to the start: a bar for each second
/// begun (three, two, one).
pub fn countdown_frame<const W: usize, const H: usize>(left: u32) -> Frame<W, H> {
    let seconds = left.div_ceil(SECOND).min(3) as usize;
    centred(|x, _| x % 2 == 0 && x / 2 < seconds, MAX_BRIGHTNESS)
}

/// The verdict.
pub fn verdict_frame<const W: usize, const H: usize>(verdict: Verdict) -> Frame<W, H> {
    let rows = match verdict {
        Verdict::Won => WON,
        Verdict::Lost => LOST,
        Verdict::Draw => DRAW,
    };
    centred(|x, y| rows[y][x] == b'#', MAX_BRIGHTNESS)
}

/// The opponent is silent: the bottom-right pixel blinks, half a second on
/// and half off, over whatever is drawn.
fn mark_silence<const W: usize, const H: usize>(frame: &mut Frame<W, H>, now: u32) {
    if W > 0 && H > 0 && (now / (SECOND / 2).max(1)).is_multiple_of(2) {
        frame.set(W - 1, H - 1, MAX_BRIGHTNESS);
    }
}

/// The race as it stands: the countdown; then the maze through `renderer`
/// following this board's marble, the opponent's replay drawn at
/// [`OPPONENT`] on top (not while the opponent is silent: the bottom-right
/// pixel blinks instead); once this board's run is over and the verdict is
/// known, the verdict.
pub fn race_frame<
    S: Scalar,
    const O: usize,
    const I: usize,
    const E: usize,
    const W: usize,
    const H: usize,
>(
    renderer: &mut Renderer<W, H>,
    race: &Race<'_, S, O, I, E>,
) -> Frame<W, H> {
    let now = race.link().now();
    let silent = race.link().silent();
    match race.status() {
        Status::Countdown(left) => {
            let mut frame = countdown_frame(left);
            if silent {
                mark_silence(&mut frame, now);
            }
            frame
        }
        Status::Decided(verdict) if race.own().game().phase() != Phase::Playing => {
            verdict_frame(verdict)
        }
        _ => {
            let own = race.own().game();
            let mut frame = renderer.render(own);
            if silent {
                mark_silence(&mut frame, now);
            } else {
                draw_ghost(
                    &mut frame,
                    own,
                    race.opponent().session().game(),
                    renderer.viewport(),
                );
            }
            frame
        }
    }
}
