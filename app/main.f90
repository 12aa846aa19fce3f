program flexmbs_main
    use flexmbs_core_kinds, only: wp
    implicit none
    print '(a)', 'flexmbs 0.1.0'
end program flexmbs_main
