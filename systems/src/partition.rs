//! The partition system: orders rays by a small integer key (volume bundle and transmit bit)
//! so that each bundle is a contiguous run, in one counting-sort pass.

use std::ops::Range;

/// Stable counting sort of item indices by `keys` (each `< num_keys`).
///
/// Outputs: `order` (item indices, grouped by key, original order within a key) and `runs`
/// (`(key, range into order)` for every non-empty key, in key order).
pub fn partition_by_key(
    keys: &[u32],
    num_keys: usize,
    order: &mut Vec<u32>,
    runs: &mut Vec<(u32, Range<usize>)>,
) {
    // Counts on the stack for the few keys a round has (bundles x transmit bit); the heap
    // only for more.
    let mut counts = [0usize; 17];
    let mut heap = Vec::new();
    let start: &mut [usize] = if num_keys < counts.len() {
        &mut counts[..num_keys + 1]
    } else {
        heap.resize(num_keys + 1, 0);
        &mut heap
    };
    for &k in keys {
        start[k as usize + 1] += 1;
    }
    for k in 0..num_keys {
        start[k + 1] += start[k];
    }
    runs.clear();
    for k in 0..num_keys {
        if start[k + 1] > start[k] {
            runs.push((k as u32, start[k]..start[k + 1]));
        }
    }
    order.clear();
    order.resize(keys.len(), 0);
    let cursor = start;
    for (i, &k) in keys.iter().enumerate() {
        order[cursor[k as usize]] = i as u32;
        cursor[k as usize] += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn groups_are_contiguous_stable_and_complete() {
        let keys = [2u32, 0, 2, 1, 0, 2];
        let (mut order, mut runs) = (Vec::new(), Vec::new());
        partition_by_key(&keys, 3, &mut order, &mut runs);
        assert_eq!(order, vec![1, 4, 3, 0, 2, 5]);
        assert_eq!(runs, vec![(0, 0..2), (1, 2..3), (2, 3..6)]);
        for (k, r) in &runs {
            assert!(order[r.clone()].iter().all(|&i| keys[i as usize] == *k));
        }
    }

    #[test]
    fn many_keys_sort_as_few() {
        // Past the stack's counts (16 keys) the counts live on the heap: same sort.
        let keys: Vec<u32> = (0..200u32).map(|i| (i * 37) % 40).collect();
        let (mut order, mut runs) = (Vec::new(), Vec::new());
        partition_by_key(&keys, 40, &mut order, &mut runs);
        assert_eq!(runs.len(), 40);
        let mut sorted: Vec<u32> = (0..200).collect();
        sorted.sort_by_key(|&i| keys[i as usize]);
        assert_eq!(order, sorted);
    }

    #[test]
    fn empty_keys_make_no_runs() {
        let (mut order, mut runs) = (vec![9], vec![(0, 0..1)]);
        partition_by_key(&[], 4, &mut order, &mut runs);
        assert!(order.is_empty() && runs.is_empty());
    }
}
