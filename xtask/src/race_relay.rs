//! The race's relay in `cargo web`'s server: a browser has no UDP and no
//! radio, so pages race through the server. A page calls `GET
//! /race?ch=N&id=ID&out=P.P` every few frames with the packets it sent since
//! its last call (`P`: each packet in lowercase hex, `.` between them; `ID`
//! its board id in hex) and is answered, as text, with the packets the other
//! pages on channel `N` sent since (the same coding). Like a radio, every page
//! on a channel hears every other; the race protocol (`marble_rolling::race`)
//! does the rest, so the relay checks nothing but the coding.
//!
//! A page unheard for [`FORGET`] is forgotten; a page that does not call for
//! its packets loses the oldest beyond [`QUEUE`] (a lost packet costs the
//! race latency, never a wrong replay).

use std::collections::{HashMap, VecDeque};
use std::sync::{Mutex, OnceLock};
use std::time::{Duration, Instant};

use marble_rolling::race::MAX_PACKET;

/// Packets kept for a page between two of its calls.
pub const QUEUE: usize = 64;
/// A page unheard this long has left the channel.
pub const FORGET: Duration = Duration::from_secs(10);
/// The most packets a call may carry.
const MOST_OUT: usize = 16;

struct Side {
    id: u32,
    queue: VecDeque<Vec<u8>>,
    seen: Instant,
}

/// The pages on each channel and the packets waiting for them.
#[derive(Default)]
pub struct Relay {
    channels: HashMap<u16, Vec<Side>>,
}

impl Relay {
    /// Page `id` on `channel` sends `out` and takes what waits for it.
    pub fn exchange(
        &mut self,
        channel: u16,
        id: u32,
        out: Vec<Vec<u8>>,
        now: Instant,
    ) -> Vec<Vec<u8>> {
        let sides = self.channels.entry(channel).or_default();
        sides.retain(|s| now.duration_since(s.seen) < FORGET || s.id == id);
        if !sides.iter().any(|s| s.id == id) {
            sides.push(Side {
                id,
                queue: VecDeque::new(),
                seen: now,
            });
        }
        for side in sides.iter_mut().filter(|s| s.id != id) {
            for packet in &out {
                if side.queue.len() == QUEUE {
                    side.queue.pop_front();
                }
                side.queue.push_back(packet.clone());
            }
        }
        let Some(me) = sides.iter_mut().find(|s| s.id == id) else {
            return Vec::new();
        };
        me.seen = now;
        me.queue.drain(..).collect()
    }
}

/// A call's arguments, or what is wrong with them.
#[derive(Debug, PartialEq, Eq)]
pub struct Call {
    pub channel: u16,
    pub id: u32,
    pub out: Vec<Vec<u8>>,
}

/// `ch=N&id=ID&out=P.P` (`out` may be empty or absent).
pub fn parse(query: &str) -> Result<Call, String> {
    let (mut channel, mut id, mut out) = (None, None, Vec::new());
    for pair in query.split('&').filter(|p| !p.is_empty()) {
        let (key, value) = pair.split_once('=').unwrap_or((pair, ""));
        match key {
            "ch" => {
                channel = Some(
                    value
                        .parse::<u16>()
                        .map_err(|_| format!("ch={value}: not a channel (0 to 65535)"))?,
                )
            }
            "id" => {
                id = Some(
                    u32::from_str_radix(value, 16)
                        .ok()
                        .filter(|&i| i != 0)
                        .ok_or_else(|| format!("id={value}: not a board id (hex, not 0)"))?,
                )
            }
            "out" => {
                for packet in value.split('.').filter(|p| !p.is_empty()) {
                    out.push(unhex(packet).ok_or_else(|| {
                        format!(
                            "out: {packet:.16}…: not a packet (hex, at most {MAX_PACKET} bytes)"
                        )
                    })?);
                }
                if out.len() > MOST_OUT {
                    return Err(format!(
                        "out: {} packets, at most {MOST_OUT} a call",
                        out.len()
                    ));
                }
            }
            other => return Err(format!("{other}: not an argument of /race (ch, id, out)")),
        }
    }
    Ok(Call {
        channel: channel.ok_or("no ch=")?,
        id: id.ok_or("no id=")?,
        out,
    })
}

fn unhex(text: &str) -> Option<Vec<u8>> {
    if !text.len().is_multiple_of(2) || text.len() / 2 > MAX_PACKET {
        return None;
    }
    (0..text.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(text.get(i..i + 2)?, 16).ok())
        .collect()
}

/// The packets as the page reads them: hex, `.` between.
pub fn coded(packets: &[Vec<u8>]) -> String {
    packets
        .iter()
        .map(|p| p.iter().map(|b| format!("{b:02x}")).collect::<String>())
        .collect::<Vec<_>>()
        .join(".")
}

/// The query of a `GET /race?…` request line in `head`, if it is one.
pub fn query(head: &str) -> Option<&str> {
    let mut words = head.lines().next()?.split_whitespace();
    let (method, target) = (words.next()?, words.next()?);
    let query = target
        .strip_prefix("/race?")
        .or_else(|| (target == "/race").then_some(""))?;
    (method == "GET").then_some(query)
}

/// The server's one relay.
fn relay() -> &'static Mutex<Relay> {
    static RELAY: OnceLock<Mutex<Relay>> = OnceLock::new();
    RELAY.get_or_init(Mutex::default)
}

/// The answer to a call: its status and body.
pub fn answer(query: &str) -> (&'static str, String) {
    match parse(query) {
        Ok(call) => {
            let mut relay = relay().lock().unwrap_or_else(|e| e.into_inner());
            let packets = relay.exchange(call.channel, call.id, call.out, Instant::now());
            ("200 OK", coded(&packets))
        }
        Err(why) => ("400 Bad Request", format!("{why}\n")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_page_on_a_channel_hears_the_others_and_not_itself() {
        let mut r = Relay::default();
        let t = Instant::now();
        assert!(r.exchange(1, 7, vec![vec![1]], t).is_empty());
        assert!(
            r.exchange(1, 9, vec![vec![2]], t).is_empty(),
            "7's packet came before 9 joined"
        );
        assert_eq!(r.exchange(1, 7, vec![], t), vec![vec![2]]);
        assert!(r.exchange(2, 5, vec![vec![3]], t).is_empty());
        assert!(
            r.exchange(1, 9, vec![], t).is_empty(),
            "another channel's packet"
        );
        assert!(r.exchange(1, 7, vec![], t).is_empty());
        // A page that does not call keeps only the newest packets.
        for i in 0..(QUEUE as u8 + 5) {
            r.exchange(1, 7, vec![vec![i]], t);
        }
        let got = r.exchange(1, 9, vec![], t);
        assert_eq!(got.len(), QUEUE);
        assert_eq!(got[0], vec![5]);
        // A page unheard for FORGET is gone: nothing waits for it.
        let later = t + FORGET + Duration::from_secs(1);
        r.exchange(1, 7, vec![vec![42]], later);
        assert!(r.exchange(1, 9, vec![], later).is_empty());
    }

    #[test]
    fn calls_read_back_and_bad_ones_say_why() {
        let call = parse("ch=3&id=1a2b&out=4d52.00ff").unwrap();
        assert_eq!(
            call,
            Call {
                channel: 3,
                id: 0x1a2b,
                out: vec![vec![0x4d, 0x52], vec![0, 0xff]]
            }
        );
        assert_eq!(parse("ch=3&id=1").unwrap().out, Vec::<Vec<u8>>::new());
        assert_eq!(coded(&call.out), "4d52.00ff");
        assert!(parse("id=1").unwrap_err().contains("ch"));
        assert!(parse("ch=1&id=0").unwrap_err().contains("not 0"));
        assert!(parse("ch=x&id=1").unwrap_err().contains("ch=x"));
        assert!(parse("ch=1&id=1&out=abc").unwrap_err().contains("out"));
        assert!(parse("ch=1&id=1&out=zz").unwrap_err().contains("out"));
        let long = "00".repeat(MAX_PACKET + 1);
        assert!(parse(&format!("ch=1&id=1&out={long}")).is_err());
        assert!(parse("ch=1&id=1&who=me").unwrap_err().contains("who"));
        assert_eq!(query("GET /race?ch=1&id=2 HTTP/1.1\r\n"), Some("ch=1&id=2"));
        assert_eq!(query("GET /race HTTP/1.1\r\n"), Some(""));
        assert_eq!(query("GET /racer HTTP/1.1\r\n"), None);
        assert_eq!(query("GET /index.html HTTP/1.1\r\n"), None);
        assert_eq!(query("HEAD /race?ch=1 HTTP/1.1\r\n"), None);
    }
}
