//! The queues from the background to the periodic task: sightings, requests, and replies owed
//! to requests that never reach the periodic task. Capacities and what happens when each is full
//! are in `vpf::guidance` (module docs).

use heapless::spsc::{Consumer, Producer, Queue};
use vpf::guidance::{Control, Sighting, CONTROL_QUEUE, REPLY_QUEUE, SIGHTING_QUEUE};
use vpf::link::ReplyRepr;

/// Slots of a heapless SPSC queue holding `items` (it keeps one slot free). heapless 0.8's ends
/// carry the slots as a const parameter, so the index arithmetic has no runtime divisor (0.9's
/// erased view keeps a division-by-zero panic path that the link check rejects).
pub const fn slots(items: usize) -> usize {
    items + 1
}

/// Slots of the sighting queue.
pub const SIGHTING_SLOTS: usize = slots(SIGHTING_QUEUE);
/// Slots of the request queue.
pub const CONTROL_SLOTS: usize = slots(CONTROL_QUEUE);
/// Slots of the owed-reply ring.
pub const REPLY_SLOTS: usize = slots(REPLY_QUEUE);

/// The three queues (in `.bss`), split once at start-up.
pub struct Queues {
    sightings: Queue<Sighting, SIGHTING_SLOTS>,
    controls: Queue<Control, CONTROL_SLOTS>,
    replies: Queue<ReplyRepr, REPLY_SLOTS>,
}

/// The background's ends.
pub struct Producers {
    /// Sightings, for the world tables.
    pub sightings: Producer<'static, Sighting, SIGHTING_SLOTS>,
    /// Requests (missions, parameters, charts).
    pub controls: Producer<'static, Control, CONTROL_SLOTS>,
    /// Replies owed to requests refused at the wire or answered "busy".
    pub replies: Producer<'static, ReplyRepr, REPLY_SLOTS>,
}

/// The periodic task's ends.
pub struct Consumers {
    /// Sightings, for the world tables.
    pub sightings: Consumer<'static, Sighting, SIGHTING_SLOTS>,
    /// Requests.
    pub controls: Consumer<'static, Control, CONTROL_SLOTS>,
    /// Owed replies.
    pub replies: Consumer<'static, ReplyRepr, REPLY_SLOTS>,
}

impl Queues {
    /// Empty queues.
    pub const fn new() -> Self {
        Queues {
            sightings: Queue::new(),
            controls: Queue::new(),
            replies: Queue::new(),
        }
    }

    /// The background's and the periodic task's ends (RTIC hands start-up the `'static`
    /// queues exactly once).
    pub fn split(&'static mut self) -> (Producers, Consumers) {
        let (s_p, s_c) = self.sightings.split();
        let (c_p, c_c) = self.controls.split();
        let (r_p, r_c) = self.replies.split();
        (
            Producers {
                sightings: s_p,
                controls: c_p,
                replies: r_p,
            },
            Consumers {
                sightings: s_c,
                controls: c_c,
                replies: r_c,
            },
        )
    }
}

impl Default for Queues {
    fn default() -> Self {
        Self::new()
    }
}
