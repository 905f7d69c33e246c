"""The seeds' own material: their cases, tables, printed formulas and notes, and the
reproductions that set gearjax's results beside them.

* `seed001`: mesh-in impact of involute helical gears (the 29/71 case, its optimal
  modification `paper_optimum`, Table 4, the note on its centre distance).
* `double_arc`: seeds 000/003, double-circular-arc gears (formulas (7) and (27)–(28),
  Tables 1–2, `gearjax reproduce dca`); `four_state`: their four-state impact model;
  `meshing_stiffness`: their Table 1 stiffness computed on the loaded contact.
* `curvilinear`: seed 002, involute curvilinear-tooth gears (`gearjax reproduce curvilinear`).

The rule: this package imports the core (geometry, tca, ltca, impact, ...); nothing in the
core imports it. Only presentation (`gearjax.cli`, notebooks, tools) may. A paper's units
(rpm, kg·mm², N·m) appear here only where its numbers are reproduced, and only on request
(`speed_rpm=`, `paper_units=True`); every function takes the engine's units by default.
"""

from . import (
    curvilinear as curvilinear,
    double_arc as double_arc,
    four_state as four_state,
    meshing_stiffness as meshing_stiffness,
    seed001 as seed001,
)
