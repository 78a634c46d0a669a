use marble_rolling::game::autopilot::Autopilot;
use marble_rolling::game::levels::LEVELS;
use marble_rolling::game::rules::{GameConfig, Phase};
use marble_rolling::game::session::{Session, SYNTHETIC_TILT};
use marble_rolling::physics::Fx;
#[test]
fn dbg() {
    let name = std::env::var("LEVEL").unwrap();
    let view = *LEVELS.iter().find(|l| l.info.name == name).unwrap();
    let mut session = Session::<Fx>::new(view, GameConfig::DEFAULT, SYNTHETIC_TILT).unwrap();
    let mut ap = Autopilot::new(&view);
    let want: u32 = std::env::var("FRAME").map(|f| f.parse().unwrap()).unwrap_or(99999);
    let mut rows = vec![];
    for frame in 0..5000u32 {
        marble_rolling::physics::world::events::DBG.store(frame == want, std::sync::atomic::Ordering::Relaxed);
        let st0 = session.game().world().stats;
        let ph = session.autopilot_frame(&mut ap);
        let w = session.game().world();
        let st = w.stats;
        rows.push((st.events - st0.events + 3 * (st.slices - st0.slices), frame, st.events - st0.events, st.slices - st0.slices, st.contacts - st0.contacts, w.marbles().iter().map(|m| (m.pos.to_f64(), m.vel.to_f64())).collect::<Vec<_>>()));
        if ph != Phase::Playing { break; }
    }
    rows.sort_by(|a, b| b.0.cmp(&a.0));
    for r in rows.iter().take(4) {
        eprintln!("frame {} events {} slices {} contacts {} {:?}", r.1, r.2, r.3, r.4, r.5);
    }
}
