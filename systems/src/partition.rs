//! The partition system: orders rays by a small integer key (volume bundle and transmit bit)
//! so that each bundle is a contiguous run, by a counting sort.

use std::ops::Range;

/// Keys up to which the counts stay on the stack (a round has a few: bundles x transmit bit).
const STACK_KEYS: usize = 16;

/// Runs up to which the indices are placed by one branchless pass per run.
const PASS_RUNS: usize = 4;

/// Stable counting sort of item indices by `keys` (each `< num_keys`).
///
/// Outputs: `order` (item indices, grouped by key, original order within a key) and `runs`
/// (`(key, range into order)` for every non-empty key, in key order).
///
/// A plain counting sort increments one counter per item, and consecutive items mostly
/// share a key, so every increment waits for the previous one to reach memory. Here the
/// counts go to four interleaved tables, and with at most `PASS_RUNS` (4) runs each run's
/// indices are written by a pass of its own whose cursor stays in a register (every item
/// is written at the cursor, which moves on only for the run's own items; the slot past
/// a run is overwritten by the next run).
pub fn partition_by_key(
    keys: &[u32],
    num_keys: usize,
    order: &mut Vec<u32>,
    runs: &mut Vec<(u32, Range<usize>)>,
) {
    let mut small = [[0usize; STACK_KEYS + 1]; 4];
    let mut heap = Vec::new();
    let start: &mut [usize] = if num_keys <= STACK_KEYS {
        for (j, &k) in keys.iter().enumerate() {
            small[j & 3][k as usize + 1] += 1;
        }
        let (sum, others) = small.split_first_mut().expect("four tables");
        for table in others {
            for k in 1..=num_keys {
                sum[k] += table[k];
            }
        }
        &mut sum[..num_keys + 1]
    } else {
        heap.resize(num_keys + 1, 0);
        for &k in keys {
            heap[k as usize + 1] += 1;
        }
        &mut heap
    };
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
    let n = keys.len();
    if runs.len() <= PASS_RUNS {
        // One slot past the end for the last run's trailing write.
        order.resize(n + 1, 0);
        for (key, range) in runs.iter() {
            let mut at = range.start;
            for (i, &k) in keys.iter().enumerate() {
                order[at] = i as u32;
                at += (k == *key) as usize;
            }
        }
        order.truncate(n);
    } else {
        order.resize(n, 0);
        let cursor = start;
        for (i, &k) in keys.iter().enumerate() {
            order[cursor[k as usize]] = i as u32;
            cursor[k as usize] += 1;
        }
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
    fn every_run_count_sorts_stably() {
        // Both placements (a pass per run up to PASS_RUNS runs, the counting scatter past
        // it) and both count tables (stack, heap), against a stable sort.
        let mut state = 0x2545_f491u32;
        for num_keys in [1usize, 2, 3, 4, 5, 8, 16, 17, 40] {
            for n in [0usize, 1, 3, 4, 5, 63, 64, 65, 1000] {
                let keys: Vec<u32> = (0..n)
                    .map(|_| {
                        state ^= state << 13;
                        state ^= state >> 17;
                        state ^= state << 5;
                        state % num_keys as u32
                    })
                    .collect();
                let (mut order, mut runs) = (vec![7; 3], Vec::new());
                partition_by_key(&keys, num_keys, &mut order, &mut runs);
                let mut sorted: Vec<u32> = (0..n as u32).collect();
                sorted.sort_by_key(|&i| keys[i as usize]);
                assert_eq!(order, sorted, "{num_keys} keys, {n} items");
                let mut at = 0;
                for (k, r) in &runs {
                    assert_eq!(r.start, at);
                    assert!(!r.is_empty());
                    assert!(order[r.clone()].iter().all(|&i| keys[i as usize] == *k));
                    at = r.end;
                }
                assert_eq!(at, n);
            }
        }
    }

    #[test]
    fn empty_keys_make_no_runs() {
        let (mut order, mut runs) = (vec![9], vec![(0, 0..1)]);
        partition_by_key(&[], 4, &mut order, &mut runs);
        assert!(order.is_empty() && runs.is_empty());
    }
}
