//! Board-agnostic firmware logic, shared by every board binary.
//!
//! embassy tasks cannot be generic, so the shape is: this module has plain
//! `async fn`s parameterised by small traits, and each board binary wraps them
//! in thin `#[embassy_executor::task]` functions that pass its own hardware:
//!
//! ```text
//!  input_task(TiltInput) ──TILT (latest)──┐
//!                       └─COMMANDS (queue)┴─> game_task ──FRAMES (latest)──> display_task(MatrixOutput)
//!                                              │ fixed-rate Ticker, calls
//!                                              └ game_tick(&mut GameState, Tilt) -> DisplayFrame
//! ```
//!
//! * [`TiltInput`]: where tilt and commands come from (accelerometer and
//!   buttons, a terminal via [`TerminalInput`], or the scripted [`DemoInput`]).
//! * [`game_task`] runs the game at [`PHYSICS_HZ`] on an embassy `Ticker`
//!   (not `Timer::after`, which rounds up to the time driver's tick and drifts).
//! * [`MatrixOutput`]: how one BCM scan step of [`crate::matrix::Scanner`]
//!   reaches LEDs (real pins, or QEMU's virtual matrix).
//! * [`Console`]: a blocking byte sink for an interactive terminal.
//!
//! **The seam for the real game** is [`GameState`] + [`game_tick`] (a
//! placeholder dot that rolls with the tilt), plus [`DemoInput`] (to be
//! replaced by the autopilot). Everything else here is plumbing.

use core::cell::Cell;
use core::future::Future;

use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::blocking_mutex::Mutex;
use embassy_sync::channel::Channel;
use embassy_sync::signal::Signal;
use embassy_time::{Duration, Ticker};

use crate::matrix::{Brightness, Frame, ScanStep, Scanner, MAX_BRIGHTNESS};

/// Display width in pixels (the micro:bit's 5×5 matrix).
pub const WIDTH: usize = 5;
/// Display height in pixels.
pub const HEIGHT: usize = 5;
/// One image for the LED matrix.
pub type DisplayFrame = Frame<WIDTH, HEIGHT>;

/// Game (physics) steps per second.
pub const PHYSICS_HZ: u32 = 50;
/// Full LED-matrix refreshes per second.
pub const REFRESH_HZ: u32 = 100;
/// Length of the headless demo, in game steps (2 s of firmware time).
pub const DEMO_STEPS: u32 = 2 * PHYSICS_HZ;

/// One g in milli-g.
pub const ONE_G_MG: i32 = 1000;

// ---------------------------------------------------------------------------
// Tilt and commands
// ---------------------------------------------------------------------------

/// An accelerometer reading in milli-g, in the board frame: `x` to the right,
/// `y` up (out of the LEDs), `z` towards the player.
///
/// It is the reaction to gravity, so a flat board reads [`Tilt::FLAT`]
/// (`y = +1000`), and lowering the right edge gives `x < 0`, which makes the
/// marble roll towards `+x`. Likewise `z < 0` rolls it towards the player
/// (down the screen).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Tilt {
    /// Right, milli-g.
    pub x: i16,
    /// Up, milli-g.
    pub y: i16,
    /// Towards the player, milli-g.
    pub z: i16,
}

impl Tilt {
    /// The board lying flat.
    pub const FLAT: Tilt = Tilt {
        x: 0,
        y: 1000,
        z: 0,
    };

    /// A 1 g reading with the given `x` and `z` components (clamped to
    /// ±1000 mg together) and `y = +sqrt(1000² - x² - z²)`.
    pub fn from_xz(x: i32, z: i32) -> Tilt {
        let x = x.clamp(-ONE_G_MG, ONE_G_MG);
        let z = z.clamp(-ONE_G_MG, ONE_G_MG);
        let horizontal = x * x + z * z;
        let y = ((ONE_G_MG * ONE_G_MG - horizontal).max(0) as u32).isqrt();
        Tilt {
            x: x as i16,
            y: y as i16,
            z: z as i16,
        }
    }
}

/// A discrete user command.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Command {
    /// Restart the current level.
    Restart,
    /// Skip to the next level.
    NextLevel,
    /// Leave the game (QEMU exits with status 0).
    Quit,
}

/// What a [`TiltInput`] produces.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum InputEvent {
    /// A new tilt reading (replaces the previous one).
    Tilt(Tilt),
    /// A command for the game.
    Command(Command),
}

/// A source of tilt readings and commands (accelerometer, keyboard, script).
pub trait TiltInput {
    /// Waits for the next event.
    fn next_event(&mut self) -> impl Future<Output = InputEvent>;
}

/// Bytes from an interactive terminal (e.g. a UART's receive queue).
pub trait ByteSource {
    /// Waits for the next received byte.
    fn read_byte(&mut self) -> impl Future<Output = u8>;
}

/// A blocking byte sink for an interactive terminal.
pub trait Console {
    /// Writes all of `bytes`.
    fn write(&mut self, bytes: &[u8]);
}

// ---------------------------------------------------------------------------
// Links between the tasks
// ---------------------------------------------------------------------------

/// The latest value of something, readable at any time (e.g. the tilt).
pub struct Latest<T: Copy> {
    value: Mutex<CriticalSectionRawMutex, Cell<T>>,
}

impl<T: Copy> Latest<T> {
    /// Holds `value` until the first [`Latest::set`].
    pub const fn new(value: T) -> Self {
        Self {
            value: Mutex::new(Cell::new(value)),
        }
    }

    /// The latest value.
    pub fn get(&self) -> T {
        self.value.lock(Cell::get)
    }

    /// Replaces the value.
    pub fn set(&self, value: T) {
        self.value.lock(|cell| cell.set(value));
    }
}

/// Latest tilt, written by [`input_task`], read by [`game_task`] each step.
pub static TILT: Latest<Tilt> = Latest::new(Tilt::FLAT);
/// Commands from [`input_task`] to [`game_task`].
pub static COMMANDS: Channel<CriticalSectionRawMutex, Command, 8> = Channel::new();
/// Latest frame from [`game_task`] to [`display_task`] (older ones are dropped).
pub static FRAMES: Signal<CriticalSectionRawMutex, DisplayFrame> = Signal::new();
/// Current level number, for status displays.
pub static LEVEL: Latest<u8> = Latest::new(1);

// ---------------------------------------------------------------------------
// Tasks
// ---------------------------------------------------------------------------

/// Forwards events from `input` to [`TILT`] and [`COMMANDS`], forever.
pub async fn input_task<I: TiltInput>(input: &mut I) -> ! {
    loop {
        match input.next_event().await {
            InputEvent::Tilt(tilt) => TILT.set(tilt),
            InputEvent::Command(command) => COMMANDS.send(command).await,
        }
    }
}

/// Why [`game_task`] returned.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GameExit {
    /// The player quit.
    Quit,
    /// The step limit given to [`game_task`] was reached (headless demo).
    StepLimit,
}

/// Runs the game at [`PHYSICS_HZ`]: each step applies pending commands, calls
/// [`game_tick`] with the latest tilt and publishes the frame on [`FRAMES`].
/// Returns on [`Command::Quit`] or after `step_limit` steps.
pub async fn game_task(step_limit: Option<u32>) -> GameExit {
    let mut state = GameState::new();
    let mut ticker = Ticker::every(Duration::from_hz(u64::from(PHYSICS_HZ)));
    let mut steps: u32 = 0;
    loop {
        ticker.next().await;
        while let Ok(command) = COMMANDS.try_receive() {
            #[cfg(feature = "defmt")]
            defmt::info!("command {}", command);
            match command {
                Command::Restart => state.restart(),
                Command::NextLevel => state.next_level(),
                Command::Quit => return GameExit::Quit,
            }
        }
        let frame = game_tick(&mut state, TILT.get());
        LEVEL.set(state.level);
        FRAMES.signal(frame);
        steps = steps.wrapping_add(1);
        #[cfg(feature = "defmt")]
        if steps.is_multiple_of(PHYSICS_HZ) {
            defmt::info!(
                "step {}: level {} dot ({}, {})/65536 px, tilt {}",
                steps,
                state.level,
                state.x,
                state.z,
                TILT.get()
            );
        }
        if step_limit.is_some_and(|limit| steps >= limit) {
            return GameExit::StepLimit;
        }
    }
}

/// Something that can show one BCM scan step on an LED matrix.
pub trait MatrixOutput {
    /// Lights row `step.row` with the columns set in `step.columns`, holds it
    /// for `step.ticks` base ticks of the board's scan clock, then returns
    /// (the caller immediately shows the next step).
    fn show(&mut self, step: ScanStep) -> impl Future<Output = ()>;
}

/// Scans the latest frame from [`FRAMES`] onto `output`, forever. A new frame
/// is taken only at the start of a refresh, so a refresh never mixes frames.
pub async fn display_task<O: MatrixOutput>(output: &mut O) -> ! {
    let mut scanner = Scanner::<WIDTH, HEIGHT>::new();
    loop {
        if scanner.at_refresh_start() {
            if let Some(frame) = FRAMES.try_take() {
                scanner.load(&frame);
            }
        }
        output.show(scanner.next_step()).await;
    }
}

// ---------------------------------------------------------------------------
// The game (placeholder: the lead replaces GameState and game_tick)
// ---------------------------------------------------------------------------

/// Fixed-point scale of [`GameState`] positions: 1 pixel = 65536 units.
const PX: i32 = 1 << 16;

/// PLACEHOLDER game state: a dot that rolls with the tilt.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GameState {
    /// Level number, from 1.
    pub level: u8,
    /// Dot column, 1/65536 px.
    pub x: i32,
    /// Dot row, 1/65536 px.
    pub z: i32,
    /// Column velocity, 1/65536 px per step.
    pub vx: i32,
    /// Row velocity, 1/65536 px per step.
    pub vz: i32,
}

impl Default for GameState {
    fn default() -> Self {
        Self::new()
    }
}

impl GameState {
    /// Level 1, dot at rest in the centre.
    pub const fn new() -> Self {
        Self::at_level(1)
    }

    const fn at_level(level: u8) -> Self {
        Self {
            level,
            x: (WIDTH as i32 - 1) * PX / 2,
            z: (HEIGHT as i32 - 1) * PX / 2,
            vx: 0,
            vz: 0,
        }
    }

    /// Restarts the current level.
    pub fn restart(&mut self) {
        *self = Self::at_level(self.level);
    }

    /// Moves on to the next level.
    pub fn next_level(&mut self) {
        *self = Self::at_level(self.level.wrapping_add(1).max(1));
    }
}

/// One axis of the placeholder physics: accelerate against the reading,
/// damp, move, bounce off the edges at half speed.
fn roll(pos: &mut i32, vel: &mut i32, reading_mg: i16, max: i32) {
    // 300 mg crosses the 5-pixel screen in about a second at 50 Hz.
    *vel -= i32::from(reading_mg) * 7 / 10;
    *vel -= *vel / 64;
    *pos += *vel;
    if *pos < 0 {
        *pos = 0;
        *vel = -*vel / 2;
    } else if *pos > max {
        *pos = max;
        *vel = -*vel / 2;
    }
}

/// PLACEHOLDER game step: rolls the dot with `tilt` and draws it
/// anti-aliased (its brightness shared between the up to four pixels it
/// overlaps, which exercises the BCM grey levels).
pub fn game_tick(state: &mut GameState, tilt: Tilt) -> DisplayFrame {
    roll(&mut state.x, &mut state.vx, tilt.x, (WIDTH as i32 - 1) * PX);
    roll(
        &mut state.z,
        &mut state.vz,
        tilt.z,
        (HEIGHT as i32 - 1) * PX,
    );

    let mut frame = DisplayFrame::new();
    let (cx, fx) = (state.x / PX, state.x % PX);
    let (cz, fz) = (state.z / PX, state.z % PX);
    let full = i64::from(MAX_BRIGHTNESS);
    for (dx, wx) in [(0, PX - fx), (1, fx)] {
        for (dz, wz) in [(0, PX - fz), (1, fz)] {
            let weight = i64::from(wx) * i64::from(wz);
            let level = (full * weight + (1i64 << 31)) >> 32;
            let (x, z) = (cx + dx, cz + dz);
            if level > 0 && x >= 0 && z >= 0 {
                frame.set(x as usize, z as usize, level as Brightness);
            }
        }
    }
    frame
}

// ---------------------------------------------------------------------------
// Inputs
// ---------------------------------------------------------------------------

/// Tilt added per key press, milli-g.
pub const KEY_TILT_STEP_MG: i32 = 100;
/// Largest tilt reachable with keys, milli-g per axis.
pub const KEY_TILT_MAX_MG: i32 = 500;

/// A key recognised by [`KeyDecoder`].
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Key {
    /// Arrow up or `w`: roll the marble up the screen (away from the player).
    Up,
    /// Arrow down or `s`.
    Down,
    /// Arrow left or `a`.
    Left,
    /// Arrow right or `d`.
    Right,
    /// Space: level the board.
    Level,
    /// `r`.
    Restart,
    /// `n`.
    Next,
    /// `q` or Ctrl-C.
    Quit,
}

/// Escape-sequence state of [`KeyDecoder`].
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
enum Escape {
    #[default]
    None,
    /// After ESC.
    Esc,
    /// After `ESC [` or `ESC O`, inside a control sequence.
    Sequence,
}

/// Decodes terminal bytes (raw mode) into [`Key`]s: arrow keys (`ESC [ A`,
/// `ESC O A`, with or without modifiers like `ESC [ 1 ; 5 A`), WASD, space,
/// `r`, `n`, `q`, Ctrl-C. Other bytes are ignored.
#[derive(Clone, Copy, Debug, Default)]
pub struct KeyDecoder {
    state: Escape,
}

impl KeyDecoder {
    /// A decoder outside any escape sequence.
    pub const fn new() -> Self {
        Self {
            state: Escape::None,
        }
    }

    /// Feeds one byte; returns a key when one is complete.
    pub fn feed(&mut self, byte: u8) -> Option<Key> {
        match self.state {
            Escape::None => Self::plain(byte, &mut self.state),
            Escape::Esc => {
                if byte == b'[' || byte == b'O' {
                    self.state = Escape::Sequence;
                    None
                } else {
                    self.state = Escape::None;
                    Self::plain(byte, &mut self.state)
                }
            }
            Escape::Sequence => match byte {
                // Parameters and intermediates: stay in the sequence.
                0x20..=0x3f => None,
                final_byte => {
                    self.state = Escape::None;
                    match final_byte {
                        b'A' => Some(Key::Up),
                        b'B' => Some(Key::Down),
                        b'C' => Some(Key::Right),
                        b'D' => Some(Key::Left),
                        _ => None,
                    }
                }
            },
        }
    }

    fn plain(byte: u8, state: &mut Escape) -> Option<Key> {
        match byte {
            0x1b => {
                *state = Escape::Esc;
                None
            }
            b'w' | b'W' => Some(Key::Up),
            b's' | b'S' => Some(Key::Down),
            b'a' | b'A' => Some(Key::Left),
            b'd' | b'D' => Some(Key::Right),
            b' ' => Some(Key::Level),
            b'r' | b'R' => Some(Key::Restart),
            b'n' | b'N' => Some(Key::Next),
            b'q' | b'Q' | 0x03 => Some(Key::Quit),
            _ => None,
        }
    }
}

/// A virtual accelerometer driven by keys: each arrow/WASD press tilts the
/// board one [`KEY_TILT_STEP_MG`] step further that way (up to
/// [`KEY_TILT_MAX_MG`]); space levels it. A terminal sends no key releases,
/// so the tilt stays until changed, like a board held tilted.
#[derive(Clone, Copy, Debug, Default)]
pub struct KeyTilt {
    decoder: KeyDecoder,
    x: i32,
    z: i32,
}

impl KeyTilt {
    /// Flat, outside any escape sequence.
    pub const fn new() -> Self {
        Self {
            decoder: KeyDecoder::new(),
            x: 0,
            z: 0,
        }
    }

    /// Feeds one terminal byte; returns the event it completes, if any.
    pub fn feed(&mut self, byte: u8) -> Option<InputEvent> {
        let step = KEY_TILT_STEP_MG;
        let (dx, dz) = match self.decoder.feed(byte)? {
            // Marble up the screen = towards -z: raise the near edge, z > 0.
            Key::Up => (0, step),
            Key::Down => (0, -step),
            // Marble right = towards +x: lower the right edge, x < 0.
            Key::Right => (-step, 0),
            Key::Left => (step, 0),
            Key::Level => (-self.x, -self.z),
            Key::Restart => return Some(InputEvent::Command(Command::Restart)),
            Key::Next => return Some(InputEvent::Command(Command::NextLevel)),
            Key::Quit => return Some(InputEvent::Command(Command::Quit)),
        };
        let max = KEY_TILT_MAX_MG;
        self.x = (self.x + dx).clamp(-max, max);
        self.z = (self.z + dz).clamp(-max, max);
        Some(InputEvent::Tilt(Tilt::from_xz(self.x, self.z)))
    }
}

/// [`TiltInput`] from an interactive terminal's bytes, via [`KeyTilt`].
pub struct TerminalInput<S: ByteSource> {
    source: S,
    keys: KeyTilt,
}

impl<S: ByteSource> TerminalInput<S> {
    /// Reads keys from `source`.
    pub const fn new(source: S) -> Self {
        Self {
            source,
            keys: KeyTilt::new(),
        }
    }
}

impl<S: ByteSource> TiltInput for TerminalInput<S> {
    async fn next_event(&mut self) -> InputEvent {
        loop {
            let byte = self.source.read_byte().await;
            if let Some(event) = self.keys.feed(byte) {
                return event;
            }
        }
    }
}

/// PLACEHOLDER for the autopilot: a scripted tilt sequence for the headless
/// demo (right, towards the player, left, away), one phase every 400 ms.
pub struct DemoInput {
    ticker: Option<Ticker>,
    phase: usize,
}

impl Default for DemoInput {
    fn default() -> Self {
        Self::new()
    }
}

impl DemoInput {
    /// Tilts `(x, z)` in milli-g, cycled through.
    const SCRIPT: [(i32, i32); 4] = [(-300, 0), (0, -300), (300, 0), (0, 300)];
    /// Time per phase.
    const PHASE: Duration = Duration::from_millis(400);

    /// Starts at the first phase.
    pub const fn new() -> Self {
        Self {
            ticker: None,
            phase: 0,
        }
    }
}

impl TiltInput for DemoInput {
    async fn next_event(&mut self) -> InputEvent {
        match &mut self.ticker {
            Some(ticker) => ticker.next().await,
            None => self.ticker = Some(Ticker::every(Self::PHASE)),
        }
        let (x, z) = Self::SCRIPT[self.phase % Self::SCRIPT.len()];
        self.phase = self.phase.wrapping_add(1);
        InputEvent::Tilt(Tilt::from_xz(x, z))
    }
}
