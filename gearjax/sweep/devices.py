"""Splitting a sweep's batch over several devices (`devices=` of the sweeps)."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np


def shard_batch(values, devices):
    """`values` with its leading (batch) axis split over `devices`: a one-axis `Mesh`
    ("batch") and `NamedSharding(mesh, P("batch"))`. The leading axis is padded to a
    multiple of the device count by repeating its last entry; the sweeps drop the padded
    rows from their results.

    On several hosts, start one process per host with `jax.distributed.initialize()` and
    pass `jax.devices()` (all hosts' devices): the same code then shards across hosts."""
    from jax.sharding import NamedSharding, PartitionSpec

    padded = _pad(jnp.asarray(values), -(-values.shape[0] // len(devices)) * len(devices))
    return jax.device_put(padded, NamedSharding(_mesh(devices), PartitionSpec("batch")))


def _mesh(devices):
    """The one-axis ("batch") mesh over `devices`."""
    from jax.sharding import Mesh

    return Mesh(np.asarray(devices), ("batch",))


def _per_device(call, batch, replicated, devices, batched):
    """`call(block, replicated)` on every device of this process, with the device's block
    of `batch`'s leading axis as `shard_batch` lays it out, and `replicated` copied there.

    Each device runs the sweep's ordinary program on its own block, so no loop of it
    waits for another device. (A `jit` of the whole batch partitioned by GSPMD must agree
    on every `vmap`ped solver loop's stopping test across devices at each iteration; with
    two forced CPU host devices jaxlib 0.10.2's runtime hung in such a program, and
    equinox's closure conversion inside `jax.shard_map` raises.) JAX dispatches each call
    asynchronously, so the devices run at once; each compiles the program for itself.

    Returns:
        The first device's output, and `batched(output)` of all devices joined into global
        arrays sharded over the mesh (`NamedSharding(mesh, P("batch"))`).
    """
    from jax.sharding import NamedSharding, PartitionSpec

    sharding = NamedSharding(_mesh(devices), PartitionSpec("batch"))
    placed = jax.tree_util.tree_map(lambda a: shard_batch(a, devices), batch)
    local = [d for d in devices if d.process_index == jax.process_index()]
    outputs = []
    for device in local:
        block = jax.tree_util.tree_map(lambda a, d=device: next(s.data for s in a.addressable_shards if s.device == d), placed)
        outputs.append(call(block, jax.device_put(replicated, device)))
    parts = [batched(out) for out in outputs]
    length = -(-jax.tree_util.tree_leaves(batch)[0].shape[0] // len(devices)) * len(devices)
    joined = jax.tree_util.tree_map(
        lambda *leaves: jax.make_array_from_single_device_arrays((length, *leaves[0].shape[1:]), sharding, list(leaves)),
        *parts)
    return outputs[0], joined


def _pad(a, length: int):
    """`a` with its leading axis padded to `length` by repeating the last entry."""
    extra = length - a.shape[0]
    return a if extra == 0 else jnp.concatenate([a, jnp.repeat(a[-1:], extra, axis=0)])


def _rows(count: int, tree):
    """The first `count` entries of every array's leading axis (drops padded rows)."""
    return jax.tree_util.tree_map(lambda a: a[:count], tree)


def _devices(devices):
    """None, or the list of devices to shard over ("all": `jax.devices()`)."""
    if devices is None:
        return None
    if isinstance(devices, str):
        if devices != "all":
            raise ValueError(f"devices must be None, 'all' or a list of jax devices; got {devices!r}")
        return jax.devices()
    devices = list(devices)
    if not devices or not all(isinstance(d, jax.Device) for d in devices):
        raise ValueError(f"devices must be None, 'all' or a non-empty list of jax devices; got {devices!r}")
    return devices
