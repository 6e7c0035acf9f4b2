"""The package of thesis listings A.1 and A.2 (the moving average filter).

Listing A.2 imports listing A.1 with ``from . import moving_avg_endpoint``,
which works only inside a package, as in the 2021 code base
(``snr/std_mods/filters/moving_average/``). This folder is that package.
"""
