"""Small native models that test the glue (not shipped): built with fmus.native_fmu.build_native_fmu."""
