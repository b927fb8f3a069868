//! Events: named functions `g(t, q, q')` whose zero crossings a run locates, and what happens
//! there (the run stops, the crossing is recorded, or a reset map gives new coordinates and rates,
//! an impact).

/// Which way `g` must cross zero for its event to happen.
///
/// ```
/// use seam::Direction;
/// assert!(Direction::Falling.crossed(1.0, -0.5));
/// assert!(!Direction::Falling.crossed(-1.0, 0.5));
/// assert!(Direction::Either.crossed(-1.0, 0.0));
/// assert!(!Direction::Rising.crossed(0.0, 1.0), "a run that starts on the surface has not crossed it");
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Direction {
    /// From negative to zero or positive.
    Rising,
    /// From positive to zero or negative.
    Falling,
    /// Either way.
    #[default]
    Either,
}

impl Direction {
    /// Whether `g` going from `before` to `after` crosses zero this way.
    pub fn crossed(self, before: f64, after: f64) -> bool {
        let rising = before < 0.0 && after >= 0.0;
        let falling = before > 0.0 && after <= 0.0;
        match self {
            Direction::Rising => rising,
            Direction::Falling => falling,
            Direction::Either => rising || falling,
        }
    }

    /// The name used in model files and reports.
    pub const fn name(self) -> &'static str {
        match self {
            Direction::Rising => "rising",
            Direction::Falling => "falling",
            Direction::Either => "either",
        }
    }
}

/// What happens at an event.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EventAction {
    /// The run ends there.
    Stop,
    /// The crossing is recorded and the run goes on.
    Record,
    /// The model's reset map gives new coordinates and rates (an impact), and the run goes on
    /// from them.
    Reset,
}

impl EventAction {
    /// The name used in model files and reports.
    pub const fn name(self) -> &'static str {
        match self {
            EventAction::Stop => "stop",
            EventAction::Record => "record",
            EventAction::Reset => "reset",
        }
    }
}

/// A model's event: its name, the direction of the crossing, and the action.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Event {
    pub name: String,
    pub direction: Direction,
    pub action: EventAction,
}
