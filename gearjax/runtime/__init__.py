"""What gearjax needs from JAX at run time: the jaxlib workarounds (`versions`), the
compilation and program caches (`cache`, `program_cache`, `program_key`) and the memory
guard (`resources`)."""
