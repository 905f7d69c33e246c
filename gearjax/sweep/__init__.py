"""Batched sweeps over operating points, in one compiled call.

The unloaded contact (TCA) does not depend on the load, so a load sweep runs it once, and
the LTCA solves all the torques in one call (`loaded_contact_analysis` with a 1-D torque:
on the CPU one load after another, each warm-started from the load below it); the
compliance matrices, which do not depend on the load either, are built once as well.

The speed enters the impact only through the velocities (`gearjax.impact`): the
first-contact search, the contact found and its local stiffness fit do not depend on it.
An impact sweep `vmap`s the impact stage over the speeds inside the map over loads; what
does not depend on the speed is not batched by `vmap`, so it is computed once per load
and the speed axis costs only the closing formulas
($v_n = \\omega_1 v_n^{(1)}$, $F_s = K_s^{1/(n+1)}((n+1) m v_n^2/2)^{n/(n+1)}$).
"""

from .designs import DesignSweep as DesignSweep, design_sweep as design_sweep
from .devices import shard_batch as shard_batch
from .loads import ImpactSweep as ImpactSweep, LoadSweep as LoadSweep, impact_sweep as impact_sweep, load_sweep as load_sweep
from .transition import regime_transition as regime_transition
