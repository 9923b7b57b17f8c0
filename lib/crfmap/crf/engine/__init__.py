"""The fast checkerboard LBP engine: ``solve.solve`` (one entry, an ``EngineResult``), the packed red/black planes
(``packed``), the numba message update (``_message_update``), and ``incremental`` for the online mapper."""
