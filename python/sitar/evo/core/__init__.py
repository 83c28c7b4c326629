"""evo.core's mirror: trajectory, sync, metrics, geometry, units, result, lie_algebra."""
