!> A bounding volume hierarchy over axis-aligned boxes, for nearest-surface queries.
!>
!> A binary tree of n leaves, one per box, and n - 1 inner nodes, in an array of 2n - 1
!> nodes with the root at 1. Each node holds the box of everything below it; an inner node
!> k has the children child(k) and child(k) + 1, a leaf has child(k) = -b for box b. Built
!> top-down: the boxes of a node are split at the median of their centres along the axis
!> where the centres spread most, so the tree is balanced (depth ceil(log2 n)) whatever
!> the sizes of the boxes, and a large box next to many small ones is one leaf, not many
!> cells. The tree only has to be valid (every node's box contains the boxes below it) for
!> a query to be exact; its shape decides how fast it is.
module ddpy_box_tree
  use ddpy_kinds, only: wp
  implicit none
  private
  public :: box_tree_build, box_distance

contains

  !> Tree over the n boxes lower(:, b) .. upper(:, b): node boxes and children (see above).
  pure subroutine box_tree_build(n, lower, upper, node_lower, node_upper, child)
    integer, intent(in) :: n
    real(wp), intent(in) :: lower(3, n), upper(3, n)
    real(wp), intent(out) :: node_lower(3, 2*n - 1), node_upper(3, 2*n - 1)
    integer, intent(out) :: child(2*n - 1)
    integer, allocatable :: perm(:), first(:), last(:)
    real(wp), allocatable :: centre(:, :)
    integer :: k, nnode, mid, axis, b, a, c
    real(wp) :: low(3), high(3)
    if (n < 1) return
    allocate(perm(n), first(2*n - 1), last(2*n - 1), centre(3, n))
    ! centre(:, b) is the centre of box perm(b): both are reordered together.
    centre = 0.5_wp*(lower + upper)
    perm = [(b, b = 1, n)]
    first(1) = 1
    last(1) = n
    nnode = 1
    k = 1
    ! Breadth first: the children of node k are made after every node before it, so every
    ! child has a larger index than its parent.
    do while (k <= nnode)
      if (first(k) == last(k)) then
        child(k) = -perm(first(k))
      else
        low = huge(1.0_wp)
        high = -huge(1.0_wp)
        do b = first(k), last(k)
          low = min(low, centre(:, b))
          high = max(high, centre(:, b))
        end do
        axis = maxloc(high - low, dim=1)
        mid = (first(k) + last(k))/2
        call select_nth(perm(first(k):last(k)), centre(:, first(k):last(k)), axis, &
                        mid - first(k) + 1)
        child(k) = nnode + 1
        first(nnode + 1) = first(k); last(nnode + 1) = mid
        first(nnode + 2) = mid + 1; last(nnode + 2) = last(k)
        nnode = nnode + 2
      end if
      k = k + 1
    end do
    ! Boxes from the leaves up: children come after their parent.
    do k = 2*n - 1, 1, -1
      if (child(k) < 0) then
        node_lower(:, k) = lower(:, -child(k))
        node_upper(:, k) = upper(:, -child(k))
      else
        a = child(k)
        c = a + 1
        node_lower(:, k) = min(node_lower(:, a), node_lower(:, c))
        node_upper(:, k) = max(node_upper(:, a), node_upper(:, c))
      end if
    end do
  end subroutine box_tree_build

  !> Reorder the columns of centre, and idx with them, so that centre(axis, nth) is the
  !> nth smallest of centre(axis, :), none after it smaller and none before it larger
  !> (Hoare's selection, median of three pivots; the columns move together, so that the
  !> passes over them read memory in order).
  pure subroutine select_nth(idx, centre, axis, nth)
    integer, intent(inout) :: idx(:)
    real(wp), intent(inout) :: centre(:, :)
    integer, intent(in) :: axis, nth
    integer :: lo, hi, i, j, itmp
    real(wp) :: pivot, tmp(3)
    lo = 1
    hi = size(idx)
    do while (lo < hi)
      pivot = median3(centre(axis, lo), centre(axis, (lo + hi)/2), centre(axis, hi))
      i = lo
      j = hi
      do
        do while (centre(axis, i) < pivot)
          i = i + 1
        end do
        do while (centre(axis, j) > pivot)
          j = j - 1
        end do
        if (i <= j) then
          itmp = idx(i); idx(i) = idx(j); idx(j) = itmp
          tmp = centre(:, i); centre(:, i) = centre(:, j); centre(:, j) = tmp
          i = i + 1
          j = j - 1
        end if
        if (i > j) exit
      end do
      ! Now lo..j <= pivot <= i..hi (and j < i); keep the part that holds nth.
      if (nth <= j) then
        hi = j
      else if (nth >= i) then
        lo = i
      else
        exit
      end if
    end do
  end subroutine select_nth

  pure real(wp) function median3(a, b, c)
    real(wp), intent(in) :: a, b, c
    median3 = max(min(a, b), min(max(a, b), c))
  end function median3

  !> Distance from x to the box lower .. upper (0 inside it).
  pure real(wp) function box_distance(x, lower, upper)
    real(wp), intent(in) :: x(3), lower(3), upper(3)
    real(wp) :: e(3)
    e = max(lower - x, 0.0_wp, x - upper)
    box_distance = sqrt(e(1)*e(1) + e(2)*e(2) + e(3)*e(3))
  end function box_distance

end module ddpy_box_tree
