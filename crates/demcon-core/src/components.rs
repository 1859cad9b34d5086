//! Connected components of a graph (union–find), labelled deterministically: the one
//! labelling used for contact graphs (demcon-graph) and conductance networks
//! (demcon-network).

/// The connected components of a graph: one label per vertex (particle or network node).
///
/// Labelling order: labels are ordered by decreasing size, ties broken by the smallest
/// vertex id in the component, so label 0 is the largest component and the result does not
/// depend on how the graph was built (edge order, parallel edges). A vertex without edges
/// is a component of size 1.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Components {
    /// Component label of each vertex.
    pub labels: Vec<u32>,
    /// Number of vertices in each component, indexed by label (non-increasing).
    pub sizes: Vec<usize>,
}

impl Components {
    /// Components of a graph with `n` vertices and the given edges (ids below `n`).
    pub fn from_pairs(n: usize, pairs: &[[u32; 2]]) -> Self {
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn find(parent: &mut [u32], mut x: u32) -> u32 {
            while parent[x as usize] != x {
                let up = parent[parent[x as usize] as usize];
                parent[x as usize] = up;
                x = up;
            }
            x
        }
        for &[p, q] in pairs {
            let (a, b) = (find(&mut parent, p), find(&mut parent, q));
            // The smaller id becomes the root: the root is the component's smallest member.
            if a < b {
                parent[b as usize] = a;
            } else if b < a {
                parent[a as usize] = b;
            }
        }
        let roots: Vec<u32> = (0..n as u32).map(|i| find(&mut parent, i)).collect();
        let mut size_of_root = vec![0usize; n];
        for &r in &roots {
            size_of_root[r as usize] += 1;
        }
        // Roots are the smallest member ids, so sorting (−size, root) is deterministic.
        let mut order: Vec<u32> = (0..n as u32).filter(|&i| roots[i as usize] == i).collect();
        order.sort_by_key(|&r| (std::cmp::Reverse(size_of_root[r as usize]), r));
        let mut label_of_root = vec![0u32; n];
        for (label, &r) in order.iter().enumerate() {
            label_of_root[r as usize] = label as u32;
        }
        Self {
            labels: roots.iter().map(|&r| label_of_root[r as usize]).collect(),
            sizes: order.iter().map(|&r| size_of_root[r as usize]).collect(),
        }
    }

    /// Number of components.
    pub fn count(&self) -> usize {
        self.sizes.len()
    }

    /// Size of the largest component (0 for an empty graph).
    pub fn largest(&self) -> usize {
        self.sizes.first().copied().unwrap_or(0)
    }

    /// Ids of the vertices in component `label`, ascending (empty for an unknown label).
    pub fn members(&self, label: u32) -> Vec<u32> {
        (0..self.labels.len() as u32)
            .filter(|&i| self.labels[i as usize] == label)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_by_size_then_smallest_member() {
        // {0,3}, {1,2,4}, {5}, {6,7}
        let c = Components::from_pairs(8, &[[2, 4], [0, 3], [1, 4], [6, 7]]);
        assert_eq!(c.sizes, vec![3, 2, 2, 1]);
        assert_eq!(c.labels, vec![1, 0, 0, 1, 0, 3, 2, 2]);
        assert_eq!(c.members(0), vec![1, 2, 4]);
        assert_eq!((c.count(), c.largest()), (4, 3));
        assert!(c.members(9).is_empty());
    }

    #[test]
    fn empty_graph() {
        let c = Components::from_pairs(0, &[]);
        assert_eq!((c.count(), c.largest()), (0, 0));
    }
}
