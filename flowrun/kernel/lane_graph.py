"""Which lane follows which: the unique successor / predecessor of every lane, as arrays.

Leaders past a lane's end can be found without asking SUMO where the road is unambiguous:
the lane has one successor (a junction-internal lane, then the next edge's lane), nothing
merges into that path (crossings do not matter ahead), and the car's route goes there.
:class:`LaneGraph` holds those facts per lane key (see :class:`~flowrun.kernel.lanes.LaneTable`).
"""

from __future__ import annotations

import numpy as np

from flowrun.kernel.lanes import LaneTable
from flowrun.types import IntArray


class LaneGraph:
    """Unique successor and predecessor of every lane (-1 where there are none or several).

    A normal lane's successor is the junction-internal lane of its only link (or the next
    lane, without internal links); an internal lane's is the lane its link leads to.

    Attributes:
        succ, pred: per lane key, the unique successor / predecessor key or -1.
        next_edge: per lane key, the edge index of the first normal lane reached through
            the successors (-1 if ambiguous).
    """

    def __init__(self, lanes: LaneTable) -> None:
        n = len(lanes.key)
        succs: list[list[int]] = [[] for _ in range(n)]
        preds: list[list[int]] = [[] for _ in range(n)]
        for lane, links in lanes.links.items():
            a = lanes.key[lane]
            for link in links:
                target = link[4] or link[0]
                b = lanes.key.get(target)
                if b is None:
                    continue
                succs[a].append(b)
                preds[b].append(a)
        self.succ: IntArray = np.array([s[0] if len(s) == 1 else -1 for s in succs], np.int64)
        self.pred: IntArray = np.array([p[0] if len(p) == 1 else -1 for p in preds], np.int64)
        self.internal = lanes.internal
        self.length = lanes.length
        self.edge_index = lanes.edge_index
        self.edge_names = lanes.edge_names
        # the same as Python lists: the walks read single entries, where lists are faster
        self.succ_l: list[int] = self.succ.tolist()
        self.pred_l: list[int] = self.pred.tolist()
        self.internal_l: list[bool] = self.internal.tolist()
        self.length_l: list[float] = self.length.tolist()
        self.edge_index_l: list[int] = self.edge_index.tolist()
