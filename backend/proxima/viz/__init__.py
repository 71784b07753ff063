"""The 3D view: a viser scene of the drones (with trails), the operator, the geofence
and the active drone, fed by bus events and served on its own port."""
