//! Animated GIFs of LED-matrix frames (`cargo sim -- ... --gif FILE`).
//!
//! Each LED becomes a `scale`×`scale` square (amber, brightness 0..=15, with a dark
//! one-pixel gap between LEDs when `scale ≥ 4`). Only the rectangle of LEDs that
//! changed since the previous image is encoded, and an unchanged image only makes
//! the previous one last longer, so a marble rolling through a maze costs a few
//! hundred bytes per GIF frame.
//!
//! An image may also hold [`NO_LED`]: a square drawn all in the gap colour, not
//! an LED (the space between the matrix and the storey maps of a level with
//! storeys, [`super::storey_maps`]).

use std::fs::File;
use std::io::{self, BufWriter};
use std::path::Path;
use std::vec;
use std::vec::Vec;

use crate::matrix::MAX_BRIGHTNESS;

/// Palette index of the gap between LEDs.
const GAP: u8 = 16;

/// An image value that is no LED: its square is drawn in the gap colour
/// (levels above it are clamped to [`MAX_BRIGHTNESS`] like any other).
pub const NO_LED: u8 = GAP;

/// The GIF palette: 16 amber brightness levels, the gap colour, padding to 32.
fn palette() -> Vec<u8> {
    let off = [20.0, 12.0, 6.0];
    let on = [255.0, 184.0, 40.0];
    let mut p = Vec::with_capacity(32 * 3);
    for b in 0..=MAX_BRIGHTNESS {
        // A gentle curve (exponent 0.7) lifts the dim levels, floor 1 and walls 3,
        // off black while keeping them well apart.
        let f = (b as f64 / MAX_BRIGHTNESS as f64).powf(0.7);
        for c in 0..3 {
            p.push((off[c] + (on[c] - off[c]) * f).round() as u8);
        }
    }
    p.extend_from_slice(&[6, 6, 6]);
    p.resize(32 * 3, 0);
    p
}

/// Writes LED images to an animated GIF.
pub(crate) struct GifRecorder {
    encoder: gif::Encoder<BufWriter<File>>,
    w: usize,
    h: usize,
    scale: usize,
    /// The last image accepted (LED brightness, row-major) and its start (1/100 s).
    last: Option<(Vec<u8>, u64)>,
    /// The encoded frame waiting for its delay (known when the next image comes).
    pending: Option<gif::Frame<'static>>,
    frames: usize,
}

impl GifRecorder {
    /// A GIF of `w`×`h` LEDs, each `scale` pixels square, at `path`.
    pub(crate) fn create(path: &Path, w: usize, h: usize, scale: usize) -> io::Result<GifRecorder> {
        let scale = scale.clamp(1, 64);
        let (pw, ph) = (w * scale, h * scale);
        if pw > u16::MAX as usize || ph > u16::MAX as usize || w == 0 || h == 0 {
            return Err(io::Error::new(io::ErrorKind::InvalidInput, "GIF too large"));
        }
        let file = BufWriter::new(File::create(path)?);
        let mut encoder =
            gif::Encoder::new(file, pw as u16, ph as u16, &palette()).map_err(io::Error::other)?;
        encoder
            .set_repeat(gif::Repeat::Infinite)
            .map_err(io::Error::other)?;
        Ok(GifRecorder {
            encoder,
            w,
            h,
            scale,
            last: None,
            pending: None,
            frames: 0,
        })
    }

    /// Adds the image `leds` (`w·h` brightness levels or [`NO_LED`], row-major)
    /// shown from `t_s` seconds on. Images closer than 1/100 s to the previous
    /// one are dropped (GIF delays are whole centiseconds).
    pub(crate) fn push(&mut self, leds: &[u8], t_s: f64) -> io::Result<()> {
        assert_eq!(leds.len(), self.w * self.h, "image size");
        let cs = (t_s * 100.0).round().max(0.0) as u64;
        let (x0, y0, x1, y1) = match &self.last {
            None => (0, 0, self.w, self.h),
            Some((prev, start)) => {
                if cs <= *start {
                    return Ok(());
                }
                match changed_box(prev, leds, self.w, self.h) {
                    None => return Ok(()),
                    Some(b) => b,
                }
            }
        };
        self.flush_pending(cs)?;
        let s = self.scale;
        let (pw, ph) = ((x1 - x0) * s, (y1 - y0) * s);
        let mut buf = vec![GAP; pw * ph];
        let gap = s >= 4;
        for py in 0..ph {
            let (ly, iy) = (y0 + py / s, py % s);
            for px in 0..pw {
                let (lx, ix) = (x0 + px / s, px % s);
                let led = leds[ly * self.w + lx];
                if led == NO_LED || (gap && (ix == s - 1 || iy == s - 1)) {
                    continue;
                }
                buf[py * pw + px] = led.min(MAX_BRIGHTNESS);
            }
        }
        let mut frame = gif::Frame::from_indexed_pixels(pw as u16, ph as u16, buf, None);
        frame.left = (x0 * s) as u16;
        frame.top = (y0 * s) as u16;
        frame.dispose = gif::DisposalMethod::Keep;
        self.pending = Some(frame);
        self.last = Some((leds.to_vec(), cs));
        Ok(())
    }

    fn flush_pending(&mut self, now_cs: u64) -> io::Result<()> {
        if let (Some(mut f), Some((_, start))) = (self.pending.take(), &self.last) {
            f.delay = now_cs.saturating_sub(*start).clamp(1, u16::MAX as u64) as u16;
            self.encoder.write_frame(&f).map_err(io::Error::other)?;
            self.frames += 1;
        }
        Ok(())
    }

    /// Writes the last image, held for `hold_s` seconds after `t_end_s`, and closes
    /// the file. Returns the GIF frames written.
    pub(crate) fn finish(mut self, t_end_s: f64, hold_s: f64) -> io::Result<usize> {
        let end = ((t_end_s + hold_s) * 100.0).round().max(0.0) as u64;
        self.flush_pending(end)?;
        let frames = self.frames;
        let mut w = self.encoder.into_inner().map_err(io::Error::other)?;
        io::Write::flush(&mut w)?;
        Ok(frames)
    }
}

/// The smallest `(x0, y0, x1, y1)` (exclusive ends) holding every LED that differs.
fn changed_box(a: &[u8], b: &[u8], w: usize, h: usize) -> Option<(usize, usize, usize, usize)> {
    let (mut x0, mut y0, mut x1, mut y1) = (w, h, 0, 0);
    for y in 0..h {
        for x in 0..w {
            if a[y * w + x] != b[y * w + x] {
                x0 = x0.min(x);
                y0 = y0.min(y);
                x1 = x1.max(x + 1);
                y1 = y1.max(y + 1);
            }
        }
    }
    (x1 > x0).then_some((x0, y0, x1, y1))
}
