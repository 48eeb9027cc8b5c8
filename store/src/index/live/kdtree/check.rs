//! Invariant checks of a [`LiveKdTree`], for tests.

use super::{LiveKdTree, NONE, is_leaf, leaf_index};

impl LiveKdTree {
    /// Checks the invariants in the module docs; `Err` names the first broken one.
    #[cfg(test)]
    pub(crate) fn check(&self) -> Result<(), String> {
        fn walk(
            t: &LiveKdTree,
            r: u32,
            lo: [f32; 3],
            hi: [f32; 3],
            is_root: bool,
            depth: usize,
        ) -> Result<(u32, usize), String> {
            if is_leaf(r) {
                let head = leaf_index(r) as u32;
                let mut l = head;
                let mut n = 0;
                let first =
                    (t.leaves[head as usize].len > 0).then(|| t.leaves[head as usize].point(0));
                while l != NONE {
                    let leaf = &t.leaves[l as usize];
                    for i in 0..leaf.len as usize {
                        let p = leaf.point(i);
                        if (0..3).any(|a| p[a] < lo[a] || p[a] >= hi[a]) {
                            return Err(format!("entry {p:?} outside its cell"));
                        }
                        if (leaf.next != NONE || l != head) && Some(p) != first {
                            return Err("chained leaf holds distinct points".into());
                        }
                    }
                    n += leaf.len;
                    l = leaf.next;
                }
                if n == 0 && !is_root {
                    return Err("empty non-root leaf".into());
                }
                return Ok((n, depth));
            }
            let node = t.inners[r as usize];
            let d = node.dim as usize;
            let mut lhi = hi;
            lhi[d] = lhi[d].min(node.split);
            let mut rlo = lo;
            rlo[d] = rlo[d].max(node.split);
            let (lc, ld) = walk(t, node.left, lo, lhi, false, depth + 1)?;
            let (rc, rd) = walk(t, node.right, rlo, hi, false, depth + 1)?;
            Ok((lc + rc, ld.max(rd)))
        }
        let (n, _) = walk(
            self,
            self.root,
            [f32::NEG_INFINITY; 3],
            [f32::INFINITY; 3],
            true,
            0,
        )?;
        if n as usize != self.len {
            return Err(format!("len {} != entries {n}", self.len));
        }
        Ok(())
    }

    /// Depth of the deepest leaf (the root leaf has depth 0).
    #[cfg(test)]
    pub(crate) fn depth(&self) -> usize {
        fn walk(t: &LiveKdTree, r: u32) -> usize {
            if is_leaf(r) {
                0
            } else {
                let n = t.inners[r as usize];
                1 + walk(t, n.left).max(walk(t, n.right))
            }
        }
        walk(self, self.root)
    }
}
