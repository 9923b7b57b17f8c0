"""What the CRF is: its potential tables (``potentials``), named configurations (``presets``), hard evidence (``evidence``)."""
