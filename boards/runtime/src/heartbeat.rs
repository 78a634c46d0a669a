//! A future that proves its task is alive each time it is polled.

use core::future::Future;
use core::pin::Pin;

/// Runs `future`, calling `beat` each time it is polled: for a task whose
/// loop lives elsewhere (`app::game_task`), being polled (every frame tick,
/// paused or not) is the proof it is not parked forever, which the
/// micro:bits' watchdog waits for. The future is pinned by the caller, in its
/// own task's storage: taken by value here it would be stored twice.
pub async fn poll_beating<F: Future>(mut beat: impl FnMut(), mut future: Pin<&mut F>) -> F::Output {
    core::future::poll_fn(|cx| {
        beat();
        future.as_mut().poll(cx)
    })
    .await
}
