!> Colouring of a mesh's elements for threaded assembly: no two elements
!> of one colour share a node, so the elements of a colour can add into the
!> global arrays at the same time (flexmbs_fe_flexible_body).
module flexmbs_fe_element_colouring
    use flexmbs_core_kinds, only: i8
    implicit none
    private

    public :: colour_elements

contains

    !> Greedy colouring: each element takes the lowest colour not used by an
    !> element sharing one of its nodes (colours as bits per node, 64 per
    !> word); the elements are then listed colour by colour, in element order:
    !> colour c is elements(colour_start(c) : colour_start(c+1)-1).
    subroutine colour_elements(connectivity, nodes, colour_start, elements)
        integer, intent(in) :: connectivity(:, :) !! (nodes per element, elements)
        integer, intent(in) :: nodes              !! nodes of the mesh
        integer, allocatable, intent(out) :: colour_start(:), elements(:)
        integer(i8), allocatable :: used(:, :)
        integer, allocatable :: colour(:)
        integer(i8) :: mask
        integer :: e, a, w, b, nwords, ncolour, ne, node
        ne = size(connectivity, 2)
        nwords = 1
        allocate (colour(ne))
        do
            allocate (used(nwords, nodes), source=0_i8)
            ncolour = 0
            each_element: do e = 1, ne
                do w = 1, nwords
                    mask = 0_i8
                    do a = 1, size(connectivity, 1)
                        mask = ior(mask, used(w, connectivity(a, e)))
                    end do
                    if (mask == not(0_i8)) cycle
                    b = trailz(not(mask))
                    colour(e) = 64 * (w - 1) + b + 1
                    ncolour = max(ncolour, colour(e))
                    do a = 1, size(connectivity, 1)
                        node = connectivity(a, e)
                        used(w, node) = ibset(used(w, node), b)
                    end do
                    cycle each_element
                end do
                exit
            end do each_element
            if (e > ne) exit
            deallocate (used)
            nwords = 2 * nwords
        end do
        allocate (colour_start(ncolour + 1), elements(ne))
        colour_start(1) = 1
        do a = 1, ncolour
            colour_start(a + 1) = colour_start(a) + count(colour == a)
        end do
        elements = [(pack([(e, e = 1, ne)], colour == a), a = 1, ncolour)]
    end subroutine colour_elements
end module flexmbs_fe_element_colouring
