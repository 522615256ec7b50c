//! The kinds of end a constraint as written may reach (its own module so
//! that `failure`, which names them, and `model`, which states them, need
//! not import each other).

/// How a constraint as written ends at a `Domain`'s argument.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DomainKind {
    /// The argument of a square root (or of a power below 1): 0 ends the
    /// branch (the constraint's derivative is infinite there), below it
    /// the root of a negative number.
    Root,
    /// The argument of a fractional power above 1: undefined below 0.
    Power,
    /// The argument of a logarithm: 0 ends it.
    Logarithm,
    /// `1 − u²` of an arcsine of `u`: 0 ends it.
    Arcsine,
    /// `1 − u²` of an arccosine of `u`: 0 ends it.
    Arccosine,
    /// What the constraint divides by (the cosine under a tangent): a
    /// pole, named when a failure happens at it.
    Pole,
}
