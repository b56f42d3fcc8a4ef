"""Image matching: pyramids, Förstner points, NCC, least-squares matching (batched).

Modules: :mod:`.pyramid` (Gaussian pyramids, level coordinates), :mod:`.interest` (Förstner
operator), :mod:`.ncc` (normalised cross-correlation, epipolar and 2-D), :mod:`.lsm`
(least-squares matching, affine / epipolar / shift models). Import from the modules directly.
"""
