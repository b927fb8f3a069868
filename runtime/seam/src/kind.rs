//! What a formulation is, and how its state is laid out: types, so that no code matches names.

use std::fmt;
use std::ops::Range;

/// One of the four formulations (the paper's Table 1). Its names are spelled here only.
///
/// ```
/// use seam::FormulationKind;
/// assert_eq!(FormulationKind::ReducedVolterra.name(), "reduced_volterra");
/// assert_eq!(FormulationKind::from_name("reduced"), Some(FormulationKind::ReducedVolterra));
/// assert_eq!(FormulationKind::from_name("kane"), Some(FormulationKind::Kane));
/// assert_eq!(FormulationKind::from_name("hamilton"), None);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum FormulationKind {
    /// Lagrange's equations with multipliers: state `[q; q']`.
    Lagrange,
    /// Maggi's equations (multiplier-free through the null space of `a`): state `[q; q']`.
    Maggi,
    /// Kane's / Gibbs-Appell's equations in the `p` quasi-velocities: state `[q; u]`.
    Kane,
    /// The paper's reduced Volterra method, `p - s` equations: state `[q; u_NI]`.
    ReducedVolterra,
}

impl FormulationKind {
    /// The formulation a run uses when none is named, among `kinds` (a model's): the paper's
    /// reduced method where it is there, else Kane's, else the first.
    ///
    /// ```
    /// use seam::FormulationKind::*;
    /// assert_eq!(seam::FormulationKind::default_among(&[Lagrange, Kane]), Kane);
    /// ```
    pub fn default_among(kinds: &[FormulationKind]) -> FormulationKind {
        [FormulationKind::ReducedVolterra, FormulationKind::Kane].into_iter().find(|k| kinds.contains(k)).unwrap_or(kinds[0])
    }

    /// All four, in the paper's order.
    pub const ALL: [FormulationKind; 4] = [FormulationKind::Lagrange, FormulationKind::Maggi, FormulationKind::Kane, FormulationKind::ReducedVolterra];

    /// The name used in files, tables and on the command line.
    pub const fn name(self) -> &'static str {
        match self {
            FormulationKind::Lagrange => "lagrange",
            FormulationKind::Maggi => "maggi",
            FormulationKind::Kane => "kane",
            FormulationKind::ReducedVolterra => "reduced_volterra",
        }
    }

    /// True when the matrix the right-hand side solves is symmetric positive definite (Maggi's
    /// `W^T M W`, Kane's and the reduced method's `M_NI`), so that `LDL^T` without pivoting
    /// solves it; Lagrange's `[M a^T; a 0]` is indefinite and needs pivoting.
    ///
    /// ```
    /// use seam::FormulationKind;
    /// assert!(FormulationKind::Kane.solves_positive_definite() && !FormulationKind::Lagrange.solves_positive_definite());
    /// ```
    pub const fn solves_positive_definite(self) -> bool {
        !matches!(self, FormulationKind::Lagrange)
    }

    /// Other spellings accepted for the name (`reduced`, `reduced-volterra`, `volterra`).
    pub const fn aliases(self) -> &'static [&'static str] {
        match self {
            FormulationKind::ReducedVolterra => &["reduced", "reduced-volterra", "volterra"],
            _ => &[],
        }
    }

    /// The kind called `name` or one of its aliases.
    pub fn from_name(name: &str) -> Option<FormulationKind> {
        FormulationKind::ALL.into_iter().find(|k| k.name() == name || k.aliases().contains(&name))
    }

    /// The kind of speeds its state carries.
    pub const fn speeds(self) -> Speeds {
        match self {
            FormulationKind::Lagrange | FormulationKind::Maggi => Speeds::Rates,
            FormulationKind::Kane | FormulationKind::ReducedVolterra => Speeds::QuasiVelocities,
        }
    }
}

impl fmt::Display for FormulationKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// What the speeds of a state are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Speeds {
    /// The rates `q'` of every coordinate, in the coordinates' order.
    Rates,
    /// Quasi-velocities `u = Y q' + Z`.
    QuasiVelocities,
}

/// How a formulation's state is laid out: `[q_kept; speeds; W?]`.
///
/// ```
/// use seam::{Speeds, StateLayout};
/// let layout = StateLayout { coordinates: vec![0, 1, 2], speeds: 3, speeds_are: Speeds::Rates, work: true };
/// assert_eq!((layout.q(), layout.speed_range(), layout.work_index(), layout.len()), (0..3, 3..6, Some(6), 7));
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StateLayout {
    /// The coordinates the state holds, as indices into the model's coordinates (all of them,
    /// unless the ignorable ones were left out).
    pub coordinates: Vec<usize>,
    /// How many speeds follow them.
    pub speeds: usize,
    /// What the speeds are.
    pub speeds_are: Speeds,
    /// True when the last entry is the work integral `W` (Eq. 80).
    pub work: bool,
}

impl StateLayout {
    /// The range of the coordinates.
    pub fn q(&self) -> Range<usize> {
        0..self.coordinates.len()
    }

    /// The range of the speeds.
    pub fn speed_range(&self) -> Range<usize> {
        self.coordinates.len()..self.coordinates.len() + self.speeds
    }

    /// The index of the work integral, when the state carries it.
    pub fn work_index(&self) -> Option<usize> {
        self.work.then(|| self.coordinates.len() + self.speeds)
    }

    /// The length of the state.
    pub fn len(&self) -> usize {
        self.coordinates.len() + self.speeds + usize::from(self.work)
    }

    /// True for a state of no entries.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// True when the state is `[q; q'; W?]` with every coordinate: what projection onto the
    /// constraints needs.
    pub fn holds_every_rate(&self, coordinates: usize) -> bool {
        self.speeds_are == Speeds::Rates && self.coordinates.len() == coordinates && self.speeds == coordinates
    }
}

/// What a model's `energy` function computes, and so what its balance with the work state `W`
/// (the power of the applied non-potential forces, of the explicit time dependence and of the
/// moving constraints' forces) means. Each is constant along a motion but for the integration
/// error.
///
/// ```
/// use seam::EnergyBalance;
/// assert_eq!(EnergyBalance::Energy.column(), "energy err");
/// assert_eq!(EnergyBalance::MovingConstraints.quantity(), "h_minus_w");
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum EnergyBalance {
    /// `E = T + V`: the kinematics do not move with time; `E - W` is constant.
    #[default]
    Energy,
    /// Jacobi's integral `h = T2 - T0 + V` (`T` split by degree in `q'`): the kinematics move
    /// with time (a frame turned or moved by a prescribed motion); `h - W` is constant.
    Jacobi,
    /// `h` as above, and a constraint moves (`b` not zero): its forces do work (a motor holding
    /// a rate), which `W` integrates too (`R . q'`, from each formulation's accelerations), so
    /// `h - W` is constant.
    MovingConstraints,
}

impl EnergyBalance {
    /// The column that reports `E(t) - E(0)` (with `E` the balance's quantity less `W`).
    pub fn column(self) -> &'static str {
        match self {
            EnergyBalance::Energy => "energy err",
            EnergyBalance::Jacobi => "jacobi err",
            EnergyBalance::MovingConstraints => "h - W err",
        }
    }

    /// What the column measures, in words (for the JSON record and the docs).
    pub fn describe(self) -> &'static str {
        match self {
            EnergyBalance::Energy => "E - W with E = T + V and W the work of the applied non-potential forces and of the explicit time dependence: constant",
            EnergyBalance::Jacobi => {
                "h - W with h = T2 - T0 + V (Jacobi's integral: the kinematics move with time) and W the work of the applied non-potential forces and of the explicit time dependence: constant"
            }
            EnergyBalance::MovingConstraints => {
                "h - W with h = T2 - T0 + V and W the work of the applied non-potential forces, of the explicit time dependence and of the moving constraints' forces (b not zero): constant"
            }
        }
    }

    /// The quantity's name in a file's columns (`energy`, `jacobi`, `h_minus_w`).
    pub fn quantity(self) -> &'static str {
        match self {
            EnergyBalance::Energy => "energy",
            EnergyBalance::Jacobi => "jacobi",
            EnergyBalance::MovingConstraints => "h_minus_w",
        }
    }

    /// A plot's title for the quantity's error over time.
    pub fn title(self) -> &'static str {
        match self {
            EnergyBalance::Energy => "energy error |E(t) - E(0)| (E = T + V - W)",
            EnergyBalance::Jacobi => "Jacobi integral error |H(t) - H(0)| (H = T2 - T0 + V - W)",
            EnergyBalance::MovingConstraints => "|H(t) - H(0)| (H = T2 - T0 + V - W; W with the moving constraints' work)",
        }
    }

    /// A plot's axis label for the quantity's error.
    pub fn axis(self) -> &'static str {
        match self {
            EnergyBalance::Energy => "|E - E(0)|",
            EnergyBalance::Jacobi | EnergyBalance::MovingConstraints => "|H - H(0)|",
        }
    }
}
