//! The display task: the latest frame scanned onto a board's LED matrix, one
//! whole refresh at a time.

use super::links::Links;
use crate::matrix::output::MatrixOutput;
use crate::matrix::Scanner;

/// Scans the latest frame from [`Links::frames`] onto `output`, forever. A
/// new frame is taken only at the start of a refresh, so a refresh never
/// mixes frames (the scanner skips a frame equal to the one on show).
pub async fn display_task<O: MatrixOutput<W, H>, const W: usize, const H: usize>(
    links: &Links<W, H>,
    output: &mut O,
) -> ! {
    let mut scanner = Scanner::<W, H>::new();
    loop {
        if let Some(frame) = links.frames.try_take() {
            scanner.load(&frame);
        }
        output.show_refresh(&mut scanner).await;
    }
}
