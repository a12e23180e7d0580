"""Python threads query one map while another thread inserts (the GIL is released in both).

Reference: the answers of the same map after each whole scan, computed
first on a map built alone. Each answer a reader gets must equal the map
after some scan between the scans finished before it asked and those
started before it got the answer (the library's concurrency contract). A
batch is many queries: each of its answers sees some whole scan, not
necessarily the same one, so batches are checked answer by answer, and a
query (count, query) as a whole.

That the GIL is really released is checked without any clock: with
sys.setswitchinterval raised so that Python threads switch only where a
call releases the GIL, a reader can see the writer inside insert() (and the
writer see a reader inside a query) only if those calls release it.
"""

import sys
import threading

import numpy as np

import umbra
from conftest import office_points, office_scans
from umbra import pred


def test_queries_from_threads_during_insertion():
    scans = office_scans(count=10)
    rng = np.random.default_rng(99)
    points = office_points(rng, 2000)
    centers = office_points(rng, 300)
    origins = office_points(rng, 100)
    directions = rng.normal(size=(100, 3))

    # name: (question, whether its answer is a batch checked element by element)
    questions = {
        "states": (lambda m: m.states(points), True),
        "spheres": (lambda m: m.spheres_free(centers, 0.3), True),
        "rays": (lambda m: m.cast_rays(origins, directions, max_range=10.0).distance, True),
        "gains": (lambda m: m.information_gains(origins[:4], [0, 90, 180, 270], 0, 100, 60, 0.0, 4.0), True),
        "count": (lambda m: m.count(pred.occupied() & pred.leaf()), False),
        "nodes": (lambda m: m.query(pred.leaf() & pred.intersects(umbra.Sphere((4, 6, 1.2), 1.5)))["log_odds"], False),
        "projection": (lambda m: m.project(0.15, 1.25, rule="any_free").cells, False),
    }

    # The answers after 0, 1, ..., 10 whole scans.
    alone = umbra.OccupancyMap(0.1)
    snapshots = [{name: ask(alone) for name, (ask, _) in questions.items()}]
    for origin, scan in scans:
        alone.insert(scan, origin, threads=1)
        snapshots.append({name: ask(alone) for name, (ask, _) in questions.items()})
    for name in questions:
        distinct = {np.asarray(s[name]).tobytes() for s in snapshots}
        assert len(distinct) > 5, f"{name}: the answers must change from scan to scan"

    def matches(name, answer, first, last):
        """Whether the answer is that of the map after one of the scans first..last (per element for a batch)."""
        candidates = [np.asarray(snapshots[k][name]) for k in range(first, last + 1)]
        answer = np.asarray(answer)
        if questions[name][1]:
            same = [(c == answer) | (np.isnan(c) & np.isnan(answer)) if c.dtype.kind == "f" else c == answer
                    for c in candidates]
            return bool(np.logical_or.reduce(same).all())
        return any(c.shape == answer.shape and (c == answer).all() for c in candidates)

    shared = umbra.OccupancyMap(0.1)
    progress = {"started": 0, "finished": 0, "inserting": False, "readers_inside": 0}
    seen = {"writer_inside": 0, "reader_inside": 0}
    failures = []
    writer_done = threading.Event()

    def writer():
        try:
            for origin, scan in scans:
                if progress["readers_inside"] > 0:
                    seen["reader_inside"] += 1
                progress["started"] += 1
                progress["inserting"] = True
                shared.insert(scan, origin, threads=1)
                progress["inserting"] = False
                progress["finished"] += 1
        finally:
            writer_done.set()

    def reader(name):
        ask = questions[name][0]
        asked = 0
        while not writer_done.is_set() or asked < 3:
            before = progress["finished"]
            progress["readers_inside"] += 1
            answer = ask(shared)
            progress["readers_inside"] -= 1
            if progress["inserting"]:
                seen["writer_inside"] += 1
            after = progress["started"]
            if not matches(name, answer, before, after):
                failures.append(f"{name}: an answer matching no map between scans {before} and {after}")
            asked += 1

    old_interval = sys.getswitchinterval()
    sys.setswitchinterval(100.0)  # threads switch only where a call releases the GIL
    try:
        threads = [threading.Thread(target=reader, args=(name,)) for name in questions]
        threads.append(threading.Thread(target=writer))
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    finally:
        sys.setswitchinterval(old_interval)

    assert not failures, failures[:5]
    assert progress["finished"] == len(scans)
    for name, (ask, _) in questions.items():
        assert matches(name, ask(shared), len(scans), len(scans))
    assert seen["writer_inside"] > 0, "no reader ever ran while insert() worked: it holds the GIL"
    assert seen["reader_inside"] > 0, "the writer never ran while a query worked: queries hold the GIL"


def test_a_reader_thread_and_a_python_rule():
    """A query whose pred.satisfies rule runs Python while another thread changes the map: no deadlock."""
    m = umbra.OccupancyMap(0.1)
    scans = office_scans(count=3)
    m.insert(*scans[0][::-1])
    calls = []

    def rule(node):
        calls.append(1)
        return node.log_odds > 0

    def change():
        for origin, scan in scans[1:]:
            m.insert(scan, origin)
            m.thresholds = umbra.Thresholds(0.55, 0.45)
            m.thresholds = umbra.Thresholds()

    t = threading.Thread(target=change)
    t.start()
    for _ in range(5):
        m.count(pred.leaf() & pred.occupied() & pred.satisfies(rule))
    t.join()
    assert calls
