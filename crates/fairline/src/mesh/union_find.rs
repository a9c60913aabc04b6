//! A union–find forest over `u32` indices (path halving; the smaller
//! root wins, so the forest does not depend on the order of the joins).

/// Root of `x` in the union–find forest `parent` (path halving).
pub(crate) fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        parent[x as usize] = parent[parent[x as usize] as usize];
        x = parent[x as usize];
    }
    x
}

/// Joins the sets of `a` and `b` in `parent` (the smaller index becomes
/// the root, so the forest does not depend on the order of the joins'
/// roots).
pub(crate) fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        parent[ra.max(rb) as usize] = ra.min(rb);
    }
}
