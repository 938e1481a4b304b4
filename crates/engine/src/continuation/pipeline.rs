//! The pipelined driver, [`Continuation::drive`]: the corrector steps along the branch on
//! the calling thread while the accepted points' stability evaluations and bifurcation
//! searches run as tasks on the rayon pool, and the points are handed out in order as they
//! are complete.
//!
//! [`Continuation::step`] runs one point's stability beside the next point's corrector and
//! waits for both (`rayon::join`); whichever side finishes first leaves its core idle
//! while the other finishes its serial parts (LU factorizations, the Schur reduction).
//! Here nothing waits for a partner: a core that is done takes the next task, which is
//! the next corrector step or the evaluation of any point not yet assessed. The corrector
//! never depends on stability (its step control and the end of the branch are
//! [`super::Walk`]'s), so the branch, its multipliers and its bifurcations are those of
//! [`Continuation::step`], computed in a different order.
//!
//! Dependencies between the tasks of the point `k`:
//!
//! * its stability: after it is accepted;
//! * the fold between `k − 1` and `k` (when the tangent's ω-component changes sign):
//!   after it is accepted;
//! * the stability changes between `k − 1` and `k` (when the numbers of unstable
//!   multipliers differ): after both stabilities;
//! * handed out: after all three, and after `k − 1`.
//!
//! The corrector runs at most [`LEAD`] points ahead of the first point not handed out
//! ([`LEAD_ONE_THREAD`] on a pool of one thread; each holds a factored Jacobian, a few MB
//! on the dual rotor).

use std::collections::VecDeque;
use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, mpsc};
use std::time::Duration;

use super::{
    BranchPoint, Continuation, ContinuationError, Current, FinishReason, StepOutcome,
    folds_between, merged_changes, stability_changes,
};
use crate::hb::HbSolution;
use crate::stability::FloquetResult;

/// Accepted points the corrector may run ahead of the first point not yet handed out.
///
/// Why twelve: a point stays out until its searches end, and a crossing search is a
/// chain of trials on one thread (at order 7 on the dual rotor seven trials of about
/// 190 ms, Hill's eigenproblem in each on one core); with four points ahead the corrector
/// soon waited and the other core idled (W4's searches used 1.53 of 2 cores). Measured
/// against four, alternating, the recordings the same (docs/performance.md, ninth
/// session): W1 5.47 / 5.27 s against 5.72 / 5.31 s, W2 37.69 / 36.24 s against 39.98 /
/// 37.52 s, W5 135.33 / 132.72 s against 136.95 / 134.48 s, W4 with the literature
/// values without the check 2.5 % less over five rounds. Each point ahead holds its
/// factored Jacobian (about 3 MB at order 3, 10 MB at order 7): the peak memory grew by
/// 10–220 MB on those workloads. On a pool of one thread (a campaign's runs, two at a
/// time on two cores) nothing runs beside the corrector, and running further ahead only
/// held more matrices: the operating map (W7) took 55.18 / 56.95 s against 52.57 /
/// 54.87 s; there [`LEAD_ONE_THREAD`] holds.
const LEAD: usize = 12;

/// [`LEAD`] on a pool of one thread: the driver's earlier value.
const LEAD_ONE_THREAD: usize = 4;

/// How long a caller that found no task of its own to run waits for a finished one
/// before it looks again.
const POLL: Duration = Duration::from_micros(200);

/// How [`Continuation::drive`] ended.
#[derive(Clone, Debug, PartialEq)]
pub enum DriveEnd {
    /// The branch ended; the observer has seen [`StepOutcome::Finished`].
    Finished(FinishReason),
    /// The observer asked to pause: every point accepted so far has been handed out, and
    /// [`Continuation::drive`] (or [`Continuation::step`]) goes on from the last one.
    Paused,
}

/// A stability evaluation: the multipliers, or the method's error message.
type Assessment = (Option<FloquetResult>, Option<String>);

/// A finished task, for the point numbered `usize` in this drive.
enum Done {
    Stability(usize, Assessment),
    Fold(usize, Option<BranchPoint>),
    Crossings(usize, Vec<BranchPoint>),
    /// A task panicked: the drive ends, and the scope passes the panic on.
    Panicked,
}

/// A task's way back to the corrector loop: sends its result, or [`Done::Panicked`] if
/// the task unwinds before it could (the loop would otherwise wait for it forever).
struct Reply(Option<mpsc::Sender<Done>>);

impl Reply {
    fn send(mut self, done: Done) {
        if let Some(tx) = self.0.take() {
            let _ = tx.send(done);
        }
    }
}

impl Drop for Reply {
    fn drop(&mut self) {
        if let Some(tx) = self.0.take() {
            let _ = tx.send(Done::Panicked);
        }
    }
}

/// An accepted point on its way out.
struct Slot {
    /// The point without stability; `None` once handed out (or for the point a resumed
    /// drive starts from, handed out before).
    point: Option<BranchPoint>,
    /// The state to step on from and to search between.
    state: Arc<Current>,
    stability: Option<Assessment>,
    /// The fold between the point before and this one.
    fold: Search<Option<BranchPoint>>,
    /// The stability changes between the point before and this one.
    crossings: Search<Vec<BranchPoint>>,
}

/// A search between a point and the one before it.
enum Search<T> {
    /// Not started: it needs a stability not known yet.
    Waiting,
    Running,
    /// Its result (also when nothing needed searching).
    Done(T),
}

impl Slot {
    fn complete(&self) -> bool {
        self.stability.is_some()
            && matches!(self.fold, Search::Done(_))
            && matches!(self.crossings, Search::Done(_))
    }
}

impl Continuation<'_> {
    /// Runs the continuation, handing every outcome to `observer` in branch order (a
    /// refused step as soon as it is refused), until the branch ends or `observer`
    /// returns [`ControlFlow::Break`]. The points already accepted when it asks to pause
    /// are still assessed and handed to it, so none is lost.
    ///
    /// With a stability method the points' evaluations and searches run on `pool` (the
    /// current one when `None`) while the corrector steps on, see the module docs; the
    /// outcomes are the same as [`Self::step`]'s. Without one, or after [`Self::step`]
    /// has left a point held, this steps.
    pub fn drive(
        &mut self,
        pool: Option<&rayon::ThreadPool>,
        observer: &mut dyn FnMut(StepOutcome) -> ControlFlow<()>,
    ) -> Result<DriveEnd, ContinuationError> {
        if self.stability.is_none()
            || self.held.is_some()
            || self.finished.is_some()
            || self.walk.finish_after.is_some()
        {
            return self.drive_by_steps(observer);
        }
        let (first, start_point) = match self.current.take() {
            Some(cur) => (cur, None),
            None => {
                let (cur, point) = self.start()?;
                (cur, Some(point))
            }
        };
        let mut walk = std::mem::take(&mut self.walk);
        let this = &*self;
        let (first, walk_ref) = ((first, start_point), &mut walk);
        let last = match pool {
            Some(p) => {
                let relay = p.current_thread_index().is_none();
                p.in_place_scope_fifo(|s| Pipe::drive(this, s, first, walk_ref, observer, relay))
            }
            None => {
                let relay = rayon::current_thread_index().is_none();
                rayon::in_place_scope_fifo(|s| {
                    Pipe::drive(this, s, first, walk_ref, observer, relay)
                })
            }
        };
        self.walk = walk;
        if let Some((state, stability)) = last {
            // the scope has ended: no task holds the state any more
            let mut state = Arc::into_inner(state).expect("the tasks ended with their scope");
            state.stability = stability;
            self.current = Some(state);
        }
        match self.walk.finish_after.take() {
            Some(f) => {
                self.finished = Some(f.clone());
                let _ = observer(StepOutcome::Finished(f.clone()));
                Ok(DriveEnd::Finished(f))
            }
            None => Ok(DriveEnd::Paused),
        }
    }

    /// [`Self::drive`] one [`Self::step`] at a time.
    fn drive_by_steps(
        &mut self,
        observer: &mut dyn FnMut(StepOutcome) -> ControlFlow<()>,
    ) -> Result<DriveEnd, ContinuationError> {
        loop {
            let out = self.step()?;
            if let StepOutcome::Finished(f) = &out {
                let f = f.clone();
                let _ = observer(out);
                return Ok(DriveEnd::Finished(f));
            }
            if observer(out).is_break() {
                // the point `step` holds (with a stability method) goes out first
                if self.held.is_some() {
                    self.settle_held();
                    if let Some(held) = self.hand_out() {
                        let _ = observer(held);
                    }
                }
                return Ok(DriveEnd::Paused);
            }
        }
    }
}

/// The state of one [`Continuation::drive`].
struct Pipe<'c, 'a, 's, 'scope> {
    cont: &'c Continuation<'a>,
    scope: &'s rayon::ScopeFifo<'scope>,
    slots: VecDeque<Slot>,
    /// The drive's number of `slots[0]`.
    front: usize,
    tx: mpsc::Sender<Done>,
    rx: mpsc::Receiver<Done>,
    /// A task panicked (see [`Reply`]).
    panicked: bool,
}

impl<'c, 'a: 'c, 's, 'scope> Pipe<'c, 'a, 's, 'scope>
where
    'c: 'scope,
{
    /// The drive from `first` (the state, with its point when it is still to be handed
    /// out) in `scope`: the last point's state and stability.
    ///
    /// With `relay` (the caller is not a thread of the scope's pool) the corrector loop
    /// runs as a task of the pool and hands the outcomes back to the caller, which
    /// observes them: a corrector on a thread outside the pool would queue each of its
    /// parallel loops behind the evaluations and wait for a pool thread to take it up.
    /// Otherwise it runs on the caller, which takes up queued tasks while it waits.
    fn drive(
        cont: &'c Continuation<'a>,
        scope: &'s rayon::ScopeFifo<'scope>,
        first: (Current, Option<BranchPoint>),
        walk: &'scope mut super::Walk,
        observer: &mut dyn FnMut(StepOutcome) -> ControlFlow<()>,
        relay: bool,
    ) -> Option<(Arc<Current>, Option<FloquetResult>)> {
        if !relay {
            let mut pipe = Pipe::new(cont, scope);
            pipe.push(first.0, first.1);
            pipe.run(walk, observer);
            return pipe.into_last();
        }
        let (out_tx, out_rx) = mpsc::channel();
        let (last_tx, last_rx) = mpsc::channel();
        let pause = Arc::new(AtomicBool::new(false));
        let paused = Arc::clone(&pause);
        scope.spawn_fifo(move |s| {
            let mut pipe = Pipe::new(cont, s);
            pipe.push(first.0, first.1);
            let mut emit = |out| {
                let _ = out_tx.send(out);
                if paused.load(Ordering::Relaxed) {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                }
            };
            pipe.run(walk, &mut emit);
            let _ = last_tx.send(pipe.into_last());
        });
        // until the corrector task ends (and drops its sender)
        for out in out_rx {
            if observer(out).is_break() {
                pause.store(true, Ordering::Relaxed);
            }
        }
        last_rx.recv().ok().flatten()
    }

    fn new(cont: &'c Continuation<'a>, scope: &'s rayon::ScopeFifo<'scope>) -> Self {
        let (tx, rx) = mpsc::channel();
        Self {
            cont,
            scope,
            slots: VecDeque::new(),
            front: 0,
            tx,
            rx,
            panicked: false,
        }
    }

    /// The corrector loop: steps while it may run ahead, takes in finished tasks, hands
    /// out complete points; returns once the branch ends or a pause was asked for and
    /// every accepted point is out.
    fn run(
        &mut self,
        walk: &mut super::Walk,
        observer: &mut dyn FnMut(StepOutcome) -> ControlFlow<()>,
    ) {
        let mut pausing = false;
        let lead = if rayon::current_num_threads() > 1 {
            LEAD
        } else {
            LEAD_ONE_THREAD
        };
        loop {
            while let Ok(done) = self.rx.try_recv() {
                self.take_in(done);
            }
            if self.panicked {
                return;
            }
            self.start_crossings();
            if self.hand_out(observer).is_break() {
                pausing = true;
            }
            let waiting = self.slots.iter().filter(|s| s.point.is_some()).count();
            let stopping = pausing || walk.finish_after.is_some();
            if stopping && waiting == 0 {
                return;
            }
            if !stopping && waiting < lead {
                let Some(last) = self.slots.back().map(|s| Arc::clone(&s.state)) else {
                    return;
                };
                match self.cont.candidate(&last, walk.ds) {
                    Ok(c) => {
                        let (point, next) = self.cont.accept(walk, &last, c);
                        self.push(next, Some(point));
                    }
                    Err(reason) => {
                        let out = Continuation::reject(walk, &self.cont.opts, reason, last.omega);
                        if observer(out).is_break() {
                            pausing = true;
                        }
                    }
                }
                continue;
            }
            match self.wait() {
                Some(done) => self.take_in(done),
                // (every sender is held by `self` or a task of this scope)
                None => return,
            }
        }
    }

    /// Adds an accepted point (`None`: the point a resumed drive starts from, handed out
    /// before, its stability in `state`) and starts its tasks.
    fn push(&mut self, state: Current, point: Option<BranchPoint>) {
        let k = self.front + self.slots.len();
        let state = Arc::new(state);
        let mut slot = Slot {
            point: None,
            state: Arc::clone(&state),
            stability: None,
            fold: Search::Done(None),
            crossings: Search::Done(Vec::new()),
        };
        match point {
            None => slot.stability = Some((state.stability.clone(), None)),
            Some(mut p) => {
                let cont = self.cont;
                let tx = Reply(Some(self.tx.clone()));
                let solution: HbSolution = p.solution.clone();
                // the assessment alone needs it (megabytes a point)
                let jacobian = p.jacobian.take();
                let at = Arc::clone(&state);
                self.scope.spawn_fifo(move |_| {
                    let result = cont.assess(&solution, jacobian.as_deref(), &at.tangent);
                    tx.send(Done::Stability(k, result));
                });
                if let Some(prev) = self.slots.back() {
                    slot.crossings = Search::Waiting;
                    if folds_between(&prev.state, &state, cont.hb.n_unknowns()) {
                        slot.fold = Search::Running;
                        let tx = Reply(Some(self.tx.clone()));
                        let (from, index) = (Arc::clone(&prev.state), p.index);
                        self.scope.spawn_fifo(move |_| {
                            tx.send(Done::Fold(k, cont.located_fold(&from, &state, index)));
                        });
                    }
                }
                slot.point = Some(p);
            }
        }
        self.slots.push_back(slot);
    }

    fn slot(&mut self, k: usize) -> Option<&mut Slot> {
        k.checked_sub(self.front)
            .and_then(|i| self.slots.get_mut(i))
    }

    fn take_in(&mut self, done: Done) {
        match done {
            Done::Stability(k, a) => {
                if let Some(s) = self.slot(k) {
                    s.stability = Some(a);
                }
            }
            Done::Fold(k, f) => {
                if let Some(s) = self.slot(k) {
                    s.fold = Search::Done(f);
                }
            }
            Done::Crossings(k, c) => {
                if let Some(s) = self.slot(k) {
                    s.crossings = Search::Done(c);
                }
            }
            Done::Panicked => self.panicked = true,
        }
    }

    /// Starts the search for stability changes between each pair of neighbours whose
    /// stabilities are both known (settled at once when their counts agree).
    fn start_crossings(&mut self) {
        for i in 1..self.slots.len() {
            let (prev, slot) = (&self.slots[i - 1], &self.slots[i]);
            if !matches!(slot.crossings, Search::Waiting) {
                continue;
            }
            let (Some((fa, _)), Some((fb, _))) = (&prev.stability, &slot.stability) else {
                continue;
            };
            let Some([fa, fb]) = stability_changes([fa.as_ref(), fb.as_ref()]) else {
                self.slots[i].crossings = Search::Done(Vec::new());
                continue;
            };
            let (cont, tx, k) = (self.cont, Reply(Some(self.tx.clone())), self.front + i);
            let (from, to) = (Arc::clone(&prev.state), Arc::clone(&slot.state));
            let (fa, fb) = (fa.clone(), fb.clone());
            let index = slot.point.as_ref().map_or(0, |p| p.index);
            self.scope.spawn_fifo(move |_| {
                let found = cont.located_crossings(&from, &to, [Some(&fa), Some(&fb)], index);
                tx.send(Done::Crossings(k, found));
            });
            self.slots[i].crossings = Search::Running;
        }
    }

    /// Hands out the complete points at the front, in order; drops the states no new task
    /// needs (a running task holds its own): all but the last, once the next point's
    /// searches have started.
    fn hand_out(
        &mut self,
        observer: &mut dyn FnMut(StepOutcome) -> ControlFlow<()>,
    ) -> ControlFlow<()> {
        let mut flow = ControlFlow::Continue(());
        for i in 0..self.slots.len() {
            let slot = &mut self.slots[i];
            if slot.point.is_none() {
                continue;
            }
            if !slot.complete() {
                break;
            }
            let (Some(mut point), Some((stability, error))) =
                (slot.point.take(), slot.stability.clone())
            else {
                break;
            };
            (point.stability, point.stability_error) = (stability, error);
            let fold = match std::mem::replace(&mut slot.fold, Search::Done(None)) {
                Search::Done(f) => f,
                _ => None,
            };
            let crossings = match std::mem::replace(&mut slot.crossings, Search::Done(Vec::new())) {
                Search::Done(c) => c,
                _ => Vec::new(),
            };
            let out = StepOutcome::Accepted {
                point: Box::new(point),
                bifurcations: merged_changes(crossings, fold),
            };
            if observer(out).is_break() {
                flow = ControlFlow::Break(());
            }
        }
        while self.slots.len() > 1
            && self.slots[0].point.is_none()
            && !matches!(self.slots[1].crossings, Search::Waiting)
        {
            self.slots.pop_front();
            self.front += 1;
        }
        flow
    }

    /// The next finished task, running queued tasks of the caller's own pool meanwhile;
    /// `None` when no task can send any more.
    fn wait(&self) -> Option<Done> {
        loop {
            match self.rx.try_recv() {
                Ok(done) => return Some(done),
                Err(mpsc::TryRecvError::Disconnected) => return None,
                Err(mpsc::TryRecvError::Empty) => {}
            }
            match rayon::yield_now() {
                Some(rayon::Yield::Executed) => {}
                // the tasks run on other threads: wait for one
                Some(rayon::Yield::Idle) => match self.rx.recv_timeout(POLL) {
                    Ok(done) => return Some(done),
                    Err(mpsc::RecvTimeoutError::Disconnected) => return None,
                    Err(mpsc::RecvTimeoutError::Timeout) => {}
                },
                // not a pool thread: nothing to run here
                None => return self.rx.recv().ok(),
            }
        }
    }

    /// The last point's state and stability, once every task has finished (the scope's
    /// end): the state the continuation goes on from.
    fn into_last(mut self) -> Option<(Arc<Current>, Option<FloquetResult>)> {
        let last = self.slots.pop_back()?;
        Some((last.state, last.stability.and_then(|(f, _)| f)))
    }
}
