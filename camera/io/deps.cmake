# camera/io: AEDAT 4.0 packets are LZ4-frame or Zstd compressed; HDF5 chunks are inflated
# with zlib outside HDF5's lock (h5_chunks.h).
pkg_check_modules(YELAN_LZ4 REQUIRED IMPORTED_TARGET liblz4)
pkg_check_modules(YELAN_ZSTD REQUIRED IMPORTED_TARGET libzstd)
pkg_check_modules(YELAN_ZLIB REQUIRED IMPORTED_TARGET zlib)
target_link_libraries(yelan_camera PUBLIC PkgConfig::YELAN_LZ4 PkgConfig::YELAN_ZSTD PkgConfig::YELAN_ZLIB)
