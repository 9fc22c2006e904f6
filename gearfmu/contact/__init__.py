"""Contact models: the registry, fractal contact, asperity load sharing, roughness."""
