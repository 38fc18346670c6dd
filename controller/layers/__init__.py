"""The layers of the chain, one per file, in CHAIN_ORDER (controller.core.chain)."""
