//! Choosing the race's radio channel and group with two buttons, before a
//! race (the micro:bit v2). Pure: the board's race task feeds it the commands
//! its buttons make ([`crate::input::buttons`]) and draws [`RaceSetup::dots`].
//!
//! * **A** (a short press, [`Command::Restart`]): the value on show goes up by
//!   one, wrapping round.
//! * **B** (a short press, [`Command::NextLevel`]): that value is chosen; the
//!   channel first, then the group, after which the setup is done.
//!
//! The other commands (the long presses) choose nothing. The value on show is
//! a count of lit dots, left to right and top to bottom on the first four rows
//! (channel 11 one dot, channel 26 sixteen; group 0 one dot, group 15
//! sixteen); the bottom row says which value it is: its left dot for the
//! channel, its right dot for the group.
//!
//! The channel is one of IEEE 802.15.4's sixteen at 2.4 GHz, the band the
//! micro:bit v2's radio uses; boards on different channels never hear each
//! other. The group is the first byte of every frame the race sends
//! (`race::air`): a board drops the frames of other groups, so two friends
//! pick a group and race each other even when other pairs share their channel.

use super::event::Command;

/// The first IEEE 802.15.4 channel at 2.4 GHz (2 405 MHz).
pub const FIRST_CHANNEL: u8 = 11;
/// The last (2 480 MHz).
pub const LAST_CHANNEL: u8 = 26;
/// Groups: 0 to 15, each shown as 1 to 16 dots like the channels.
pub const GROUPS: u8 = 16;

/// A radio channel and group.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Tuning {
    /// [`FIRST_CHANNEL`] ..= [`LAST_CHANNEL`].
    pub channel: u8,
    /// 0 .. [`GROUPS`].
    pub group: u8,
}

impl Tuning {
    /// Channel 11, group 0: what a board offers before anyone chooses.
    pub const DEFAULT: Tuning = Tuning {
        channel: FIRST_CHANNEL,
        group: 0,
    };

    /// The tuning of `channel` and `group`, if both are in range.
    pub const fn new(channel: u8, group: u8) -> Option<Tuning> {
        if channel >= FIRST_CHANNEL && channel <= LAST_CHANNEL && group < GROUPS {
            Some(Tuning { channel, group })
        } else {
            None
        }
    }
}

impl Default for Tuning {
    fn default() -> Self {
        Tuning::DEFAULT
    }
}

/// The value being chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Field {
    /// The channel.
    Channel,
    /// The group.
    Group,
}

/// The chooser: the channel, then the group.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RaceSetup {
    field: Field,
    tuning: Tuning,
}

impl RaceSetup {
    /// Starts on the channel, from `start` (the last choice, or
    /// [`Tuning::DEFAULT`]); a `start` out of range starts from the default's
    /// value for that field.
    pub const fn new(start: Tuning) -> Self {
        let tuning = match Tuning::new(start.channel, start.group) {
            Some(t) => t,
            None => match (
                Tuning::new(start.channel, 0),
                Tuning::new(FIRST_CHANNEL, start.group),
            ) {
                (Some(t), _) | (_, Some(t)) => t,
                (None, None) => Tuning::DEFAULT,
            },
        };
        RaceSetup {
            field: Field::Channel,
            tuning,
        }
    }

    /// The value being chosen.
    pub const fn field(&self) -> Field {
        self.field
    }

    /// The channel and group as they stand.
    pub const fn tuning(&self) -> Tuning {
        self.tuning
    }

    /// Takes a command: `Some` once the group is chosen (the setup is then
    /// over; later commands start choosing again, from the channel).
    pub fn command(&mut self, command: Command) -> Option<Tuning> {
        match (command, self.field) {
            (Command::Restart, Field::Channel) => {
                self.tuning.channel = if self.tuning.channel >= LAST_CHANNEL {
                    FIRST_CHANNEL
                } else {
                    self.tuning.channel + 1
                };
                None
            }
            (Command::Restart, Field::Group) => {
                self.tuning.group = (self.tuning.group + 1) % GROUPS;
                None
            }
            (Command::NextLevel, Field::Channel) => {
                self.field = Field::Group;
                None
            }
            (Command::NextLevel, Field::Group) => {
                self.field = Field::Channel;
                Some(self.tuning)
            }
            _ => None,
        }
    }

    /// The value on show, from 1 (channel 11, group 0) to 16.
    pub const fn count(&self) -> u8 {
        match self.field {
            Field::Channel => self.tuning.channel - FIRST_CHANNEL + 1,
            Field::Group => self.tuning.group + 1,
        }
    }

    /// The 5×5 picture, row by row (`true`: lit): [`RaceSetup::count`] dots
    /// on the first four rows in reading order, and on the bottom row the
    /// left dot for the channel or the right one for the group.
    pub fn dots(&self) -> [[bool; 5]; 5] {
        let mut dots = [[false; 5]; 5];
        let count = usize::from(self.count());
        for (i, dot) in dots.iter_mut().take(4).flatten().enumerate() {
            *dot = i < count;
        }
        let marker = match self.field {
            Field::Channel => 0,
            Field::Group => 4,
        };
        dots[4][marker] = true;
        dots
    }
}

/// Whether the buttons held at power-on ask for a race: **A** alone, unless
/// the board is waking from its idle sleep (the button that woke it may still
/// be down, and a wake-up resumes the game).
pub const fn race_at_power_on(a_held: bool, b_held: bool, woke_from_sleep: bool) -> bool {
    a_held && !b_held && !woke_from_sleep
}
