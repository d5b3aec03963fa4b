"""Flow's sentinel values, returned where Flow's own getters return them.

flowrun's arrays use ``inf`` / ``-1`` / ``nan`` internally; the Flow-compatible API (``k.vehicle``
getters, ``k.network`` getters, Flow-style controllers, Flow's emission CSV) gives these
numbers instead, because Flow code tests for them.
"""

#: Flow's value of a number it does not know (an unknown vehicle or edge; ``get_speed(None)``).
FLOW_ERROR = -1001.0
#: Flow's gap (m) to a leader or follower that does not exist.
FLOW_NO_GAP = 1000.0
