//! Non-fatal findings, for the user to read: one [`Diagnostic`] type for every stage that
//! reports them (contact detection in demcon-graph, boundary-condition resolution in
//! demcon-network), so a run collects them in one list and prints them the same way.

use std::fmt;

/// A non-fatal finding of a stage, to be shown to the user (its `Display` is the line the
/// CLI prints).
#[derive(Debug, Clone, PartialEq)]
pub enum Diagnostic {
    /// Contact detection: particles with no contact (rattlers); they make a network
    /// singular if not excluded.
    Rattlers {
        /// How many.
        count: usize,
    },
    /// Contact detection: particles with exactly one contact (dead ends of the network).
    SingleContact {
        /// How many.
        count: usize,
    },
    /// Contact detection: pairs whose spheres overlap (negative gap).
    Overlaps {
        /// How many pairs.
        count: usize,
        /// Largest overlap relative to R_p + R_q (dimensionless, > 0).
        max_relative: f64,
    },
    /// Contact detection: the reached coordination exceeds the target by more than the
    /// tolerance, because several pairs share the selected gap.
    CoordinationOvershoot {
        /// Requested Z (contacts per particle).
        target: f64,
        /// Reached Z (contacts per particle).
        reached: f64,
    },
    /// Contact detection: the graph has more than one connected component (rattlers
    /// included).
    Disconnected {
        /// Number of components.
        components: usize,
        /// Particles in the largest component.
        largest: usize,
    },
    /// Boundary conditions: floating clusters (reaching no fixed value) were left out of
    /// the solve.
    FloatingExcluded {
        /// Number of clusters.
        clusters: usize,
        /// Number of nodes in them.
        nodes: usize,
        /// Size of the largest one (nodes).
        largest: usize,
    },
    /// Boundary conditions: floating clusters are kept as unknowns (transient solvers only).
    FloatingKept {
        /// Number of clusters.
        clusters: usize,
        /// Number of nodes in them.
        nodes: usize,
        /// Size of the largest one (nodes).
        largest: usize,
    },
}

impl fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Rattlers { count } => write!(f, "{count} rattlers (particles with no contact)"),
            Self::SingleContact { count } => write!(f, "{count} particles with a single contact"),
            Self::Overlaps { count, max_relative } => write!(
                f,
                "{count} overlapping pairs, largest overlap {:.3} % of R_p + R_q",
                100.0 * max_relative
            ),
            Self::CoordinationOvershoot { target, reached } => write!(
                f,
                "coordination {reached:.4} overshoots the target {target} (pairs with equal gaps)"
            ),
            Self::Disconnected { components, largest } => write!(
                f,
                "{components} connected components; the largest holds {largest} particles"
            ),
            Self::FloatingExcluded {
                clusters,
                nodes,
                largest,
            } => write!(
                f,
                "{nodes} particle(s) in {clusters} floating cluster(s) (reaching no fixed value) excluded; largest has {largest}"
            ),
            Self::FloatingKept {
                clusters,
                nodes,
                largest,
            } => write!(
                f,
                "{nodes} particle(s) in {clusters} floating cluster(s) (reaching no fixed value) kept; largest has {largest}"
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Diagnostic;

    #[test]
    fn text_is_the_line_users_read() {
        let lines = [
            (
                Diagnostic::Rattlers { count: 37 },
                "37 rattlers (particles with no contact)",
            ),
            (
                Diagnostic::Overlaps {
                    count: 2,
                    max_relative: 0.0012345,
                },
                "2 overlapping pairs, largest overlap 0.123 % of R_p + R_q",
            ),
            (
                Diagnostic::FloatingExcluded {
                    clusters: 2,
                    nodes: 3,
                    largest: 2,
                },
                "3 particle(s) in 2 floating cluster(s) (reaching no fixed value) excluded; largest has 2",
            ),
        ];
        for (d, text) in lines {
            assert_eq!(d.to_string(), text);
        }
    }
}
