"""The greedy mean-link agglomeration in plain Python (dicts and heapq), the reference of the numba kernel.

The algorithm of the research prototype (``benchmarks/experiment_learned_grouping.py``, ``agglomerate`` with
``mode="mean"``): merge the two clusters with the largest mean link probability over the edges between them
while it exceeds the floor; the survivor is the side with more neighbouring clusters (the smaller number at
equal counts); heap ties by (smaller node, larger node).
"""

import heapq


def reference_merges(i, j, probability, floor):
    """``[(child, survivor, link), ...]`` in merge order."""
    adjacency = {}
    for a, b, p in zip(i, j, probability, strict=True):
        a, b = min(a, b), max(a, b)
        adjacency.setdefault(a, {})[b] = [p, 1]
        adjacency.setdefault(b, {})[a] = [p, 1]

    def mean(entry):
        return entry[0] / entry[1]

    heap = [(-mean(e), a, b) for a, nbs in adjacency.items() for b, e in nbs.items() if a < b and mean(e) > floor]
    heapq.heapify(heap)
    merged, merges = set(), []
    while heap:
        value, a, b = heapq.heappop(heap)
        if a in merged or b in merged:
            continue
        entry = adjacency[a].get(b)
        if entry is None or -value != mean(entry):
            continue
        if len(adjacency[a]) < len(adjacency[b]):
            a, b = b, a
        merged.add(b)
        merges.append((b, a, -value))
        big, small = adjacency[a], adjacency.pop(b)
        del big[b]
        for c, (total, count) in small.items():
            if c == a:
                continue
            other = adjacency[c]
            del other[b]
            if c in big:
                big[c][0] += total
                big[c][1] += count
            else:
                big[c] = [total, count]
            other[a] = big[c]
            if mean(big[c]) > floor:
                heapq.heappush(heap, (-mean(big[c]), min(a, c), max(a, c)))
    return merges
