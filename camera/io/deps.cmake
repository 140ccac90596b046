# camera/io: AEDAT 4.0 packets are LZ4-frame or Zstd compressed.
pkg_check_modules(YELAN_LZ4 REQUIRED IMPORTED_TARGET liblz4)
pkg_check_modules(YELAN_ZSTD REQUIRED IMPORTED_TARGET libzstd)
target_link_libraries(yelan_camera PUBLIC PkgConfig::YELAN_LZ4 PkgConfig::YELAN_ZSTD)
