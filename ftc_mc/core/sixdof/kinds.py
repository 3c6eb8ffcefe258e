"""``Reconfig.kind`` of the 6-DOF family's controllers (after 0 nominal and 1
reconfiguring, the paper's): imported by the lock-turn law, the side monitor
and the selection, so that none imports another for them."""

LOCK_TURN = 2
"""A ``controller: lock_turn`` design: the paper's reconfiguring loop until the
side monitor names an elevon, then the lock-turn controller of that side
(:mod:`ftc_mc.core.sixdof.lockturn`)."""

SELECTED_TURN = 3
"""A ``controller: lock_turn_selected`` design: the selection of eqs. 45-47
chooses among c0, c1 and the lock-turn controllers of either side
(:mod:`ftc_mc.core.sixdof.selection`)."""
