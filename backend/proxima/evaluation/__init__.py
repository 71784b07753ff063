"""Evaluation, apart from the live engine: how well a checkpoint and the decision path
do on held-out data. Nothing here is on the live path; streams are replayed through the
engine's own code (`proxima.engine`), so a figure cannot drift from what the engine does.

- `metrics`: a checkpoint on a split's test windows (accuracy, macro F1, per class,
  per clip, per view).
- `protocols`: train and score once per evaluation protocol (the model card's table).
- `model_card`: a checkpoint's Markdown card from its metadata and protocol results.
- `stitch`: long replay streams stitched from dataset clips, with a ground-truth script.
- `scoring`: a run's commands against that ground truth (hits, misses, wrong, latency).
- `replay`: stitched streams through the real `Engine`, and the fast offline replay
  (the engine's stream pipeline once, then its filter, hand evidence and controller for
  each decision setting).
- `latency`: the onset -> command benchmark and the tuning of the decision settings.
- `still`: what an armed operator standing still is commanded to do.
- `temporal_errors`: where a temporal-split model goes wrong, against a nearest-
  neighbour check.
- `plots`: the pictures of the above.
- `cli`: `proxima evaluate`, `proxima protocols`, `proxima model-card` and `proxima stitch`.
"""
