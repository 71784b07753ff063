"""Federated training with Flower: each drone trains on its own data, the ground station
averages. See docs/federated.md. Heavy imports (flwr, torch) stay in the submodules."""
