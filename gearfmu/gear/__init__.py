"""The gear pair: specs, geometry, stiffness, deviations, loaded mesh, thermal state."""
