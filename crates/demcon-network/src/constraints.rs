//! Resolved boundary conditions: which nodes carry a fixed value (Dirichlet), which are
//! excluded because their cluster reaches no fixed value, and which are free unknowns.

use crate::error::SolveError;
use crate::network::Network;

/// What to do with nodes whose connected cluster contains no fixed value ("floating":
/// rattlers, detached grains). Their steady state is undetermined, so a steady solve
/// cannot include them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FloatingPolicy {
    /// Refuse: [`SolveError::FloatingCluster`] names their number and size.
    #[default]
    Fail,
    /// Leave them out of the solve (reported as a [`Diagnostic`]); their values are not
    /// computed (see [`crate::Solution::excluded`]).
    Exclude,
    /// Keep them as unknowns. Only for transient solvers, where their own heat capacity
    /// makes the problem well posed; a steady solve refuses them.
    Keep,
}

/// Role of a node in a solve.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NodeKind {
    /// An unknown.
    Free,
    /// Its value is imposed.
    Fixed,
    /// Left out of the solve (floating cluster excluded by [`FloatingPolicy::Exclude`]).
    Excluded,
}

/// A non-fatal finding of the resolution (the variants `FloatingExcluded`, `FloatingKept`),
/// to be shown to the user.
pub use demcon_core::Diagnostic;

/// Resolved constraints of one network: the only form of boundary condition the solvers
/// accept, so "fixed values are consistent and floating clusters are handled" is a
/// property of the type.
#[derive(Debug, Clone, PartialEq)]
pub struct Constraints {
    kinds: Vec<NodeKind>,
    fixed_nodes: Vec<u32>,
    fixed_values: Vec<f64>,
    excluded: Vec<u32>,
    floating_kept: Vec<u32>,
    diagnostics: Vec<Diagnostic>,
}

impl Constraints {
    /// Role of every node.
    pub fn kinds(&self) -> &[NodeKind] {
        &self.kinds
    }

    /// Fixed nodes, sorted and unique.
    pub fn fixed_nodes(&self) -> &[u32] {
        &self.fixed_nodes
    }

    /// Values at [`Self::fixed_nodes`] (K or V).
    pub fn fixed_values(&self) -> &[f64] {
        &self.fixed_values
    }

    /// Excluded nodes, sorted.
    pub fn excluded(&self) -> &[u32] {
        &self.excluded
    }

    /// Nodes of floating clusters kept as unknowns ([`FloatingPolicy::Keep`]), sorted.
    pub fn floating_kept(&self) -> &[u32] {
        &self.floating_kept
    }

    /// Number of free unknowns.
    pub fn n_free(&self) -> usize {
        self.kinds.len() - self.fixed_nodes.len() - self.excluded.len()
    }

    /// Non-fatal findings (floating clusters excluded or kept).
    pub fn diagnostics(&self) -> &[Diagnostic] {
        &self.diagnostics
    }

    /// Writes the fixed values into a nodal vector.
    pub fn impose(&self, values: &mut [f64]) {
        for (&p, &v) in self.fixed_nodes.iter().zip(&self.fixed_values) {
            values[p as usize] = v;
        }
    }
}

/// Resolves fixed-value sets into [`Constraints`].
///
/// `sets[k] = (nodes, value)` fixes every listed node to `value` (K or V). A node listed in
/// two sets must receive the same value. Clusters that contain no fixed node are handled by
/// `policy`. With no set at all, every node is floating: `Fail` gives
/// [`SolveError::NoFixedValue`], `Keep` gives an all-free problem (a transient with
/// adiabatic boundaries).
///
/// # Errors
/// [`SolveError::EmptyFixedSet`], [`SolveError::NodeOutOfRange`],
/// [`SolveError::InvalidParameter`] for a non-finite value, [`SolveError::ConflictingFixed`],
/// [`SolveError::NoFixedValue`], [`SolveError::FloatingCluster`].
pub fn resolve_fixed(
    net: &Network,
    sets: &[(Vec<u32>, f64)],
    policy: FloatingPolicy,
) -> Result<Constraints, SolveError> {
    let n = net.n_nodes();
    let mut value_of: Vec<Option<(f64, usize)>> = vec![None; n];
    for (k, (nodes, value)) in sets.iter().enumerate() {
        if nodes.is_empty() {
            return Err(SolveError::EmptyFixedSet { set: k });
        }
        if !value.is_finite() {
            return Err(SolveError::invalid(
                format!("fixed set {k} value"),
                value,
                "must be a finite number",
            ));
        }
        for &p in nodes {
            let slot = value_of
                .get_mut(p as usize)
                .ok_or_else(|| SolveError::NodeOutOfRange {
                    what: format!("fixed set {k}"),
                    node: p as u64,
                    n_nodes: n,
                })?;
            match *slot {
                None => *slot = Some((*value, k)),
                Some((v, first_set)) if v != *value => {
                    return Err(SolveError::ConflictingFixed {
                        node: p,
                        first: v,
                        first_set,
                        second: *value,
                        second_set: k,
                    });
                }
                Some(_) => {}
            }
        }
    }
    if sets.is_empty() && policy != FloatingPolicy::Keep {
        return Err(SolveError::NoFixedValue);
    }
    let comps = net.components();
    let mut anchored = vec![false; comps.count()];
    for (p, v) in value_of.iter().enumerate() {
        if v.is_some() {
            anchored[comps.labels[p] as usize] = true;
        }
    }
    let mut clusters = 0usize;
    let mut floating_nodes = 0usize;
    let mut largest = 0usize;
    let mut largest_label = 0u32;
    for (c, (&a, &size)) in anchored.iter().zip(&comps.sizes).enumerate() {
        if !a {
            clusters += 1;
            floating_nodes += size;
            if size > largest {
                largest = size;
                largest_label = c as u32;
            }
        }
    }
    if clusters > 0 && policy == FloatingPolicy::Fail {
        let example = comps.labels.iter().position(|&l| l == largest_label).unwrap_or(0) as u32;
        return Err(SolveError::FloatingCluster {
            clusters,
            nodes: floating_nodes,
            largest,
            example,
        });
    }
    let mut kinds = vec![NodeKind::Free; n];
    let mut fixed_nodes = Vec::new();
    let mut fixed_values = Vec::new();
    let mut excluded = Vec::new();
    let mut floating_kept = Vec::new();
    for p in 0..n {
        if let Some((v, _)) = value_of[p] {
            kinds[p] = NodeKind::Fixed;
            fixed_nodes.push(p as u32);
            fixed_values.push(v);
        } else if !anchored[comps.labels[p] as usize] {
            if policy == FloatingPolicy::Exclude {
                kinds[p] = NodeKind::Excluded;
                excluded.push(p as u32);
            } else {
                floating_kept.push(p as u32);
            }
        }
    }
    let mut diagnostics = Vec::new();
    if clusters > 0 {
        diagnostics.push(match policy {
            FloatingPolicy::Exclude => Diagnostic::FloatingExcluded {
                clusters,
                nodes: floating_nodes,
                largest,
            },
            _ => Diagnostic::FloatingKept {
                clusters,
                nodes: floating_nodes,
                largest,
            },
        });
    }
    Ok(Constraints {
        kinds,
        fixed_nodes,
        fixed_values,
        excluded,
        floating_kept,
        diagnostics,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_clusters() -> Network {
        // 0-1-2 chain, 3-4 pair, 5 isolated.
        Network::new(6, &[[0, 1], [1, 2], [3, 4]]).unwrap()
    }

    #[test]
    fn floating_clusters_fail_exclude_or_keep() {
        let net = two_clusters();
        let sets = vec![(vec![0], 1.0)];
        match resolve_fixed(&net, &sets, FloatingPolicy::Fail) {
            Err(SolveError::FloatingCluster {
                clusters,
                nodes,
                largest,
                example,
            }) => {
                assert_eq!((clusters, nodes, largest, example), (2, 3, 2, 3));
            }
            other => panic!("expected FloatingCluster, got {other:?}"),
        }
        let c = resolve_fixed(&net, &sets, FloatingPolicy::Exclude).unwrap();
        assert_eq!(c.excluded(), &[3, 4, 5]);
        assert_eq!(c.n_free(), 2);
        assert_eq!(
            c.diagnostics(),
            &[Diagnostic::FloatingExcluded {
                clusters: 2,
                nodes: 3,
                largest: 2
            }]
        );
        assert!(
            c.diagnostics()[0]
                .to_string()
                .contains("3 particle(s) in 2 floating")
        );
        let k = resolve_fixed(&net, &sets, FloatingPolicy::Keep).unwrap();
        assert_eq!(k.floating_kept(), &[3, 4, 5]);
        assert_eq!(k.n_free(), 5);
    }

    #[test]
    fn bad_sets_are_rejected() {
        let net = two_clusters();
        assert_eq!(
            resolve_fixed(&net, &[(vec![], 1.0)], FloatingPolicy::Exclude),
            Err(SolveError::EmptyFixedSet { set: 0 })
        );
        assert!(matches!(
            resolve_fixed(&net, &[(vec![9], 1.0)], FloatingPolicy::Exclude),
            Err(SolveError::NodeOutOfRange { node: 9, .. })
        ));
        assert!(matches!(
            resolve_fixed(&net, &[(vec![0], f64::NAN)], FloatingPolicy::Exclude),
            Err(SolveError::InvalidParameter { .. })
        ));
        assert!(matches!(
            resolve_fixed(
                &net,
                &[(vec![0, 1], 1.0), (vec![1, 2], 2.0)],
                FloatingPolicy::Exclude
            ),
            Err(SolveError::ConflictingFixed {
                node: 1,
                first_set: 0,
                second_set: 1,
                ..
            })
        ));
        // The same value twice is not a conflict.
        let c = resolve_fixed(
            &net,
            &[(vec![0, 1], 1.0), (vec![1, 3], 1.0)],
            FloatingPolicy::Exclude,
        )
        .unwrap();
        assert_eq!(c.fixed_nodes(), &[0, 1, 3]);
        assert_eq!(c.excluded(), &[5]);
        assert_eq!(
            resolve_fixed(&net, &[], FloatingPolicy::Fail),
            Err(SolveError::NoFixedValue)
        );
        assert_eq!(
            resolve_fixed(&net, &[], FloatingPolicy::Keep).unwrap().n_free(),
            6
        );
    }
}
