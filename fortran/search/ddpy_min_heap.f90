!> A binary min-heap of (key, item) pairs in caller-owned arrays, for best-first searches.
!>
!> The caller holds key(capacity), item(capacity) and the count n (0 = empty); the smallest
!> key is at position 1. Pushing beyond the capacity is the caller's error: size the
!> arrays by the most entries the search can hold.
module ddpy_min_heap
  use ddpy_kinds, only: wp
  implicit none
  private
  public :: heap_push, heap_pop

contains

  !> Add (k, it) to the heap of n entries.
  pure subroutine heap_push(k, it, n, key, item)
    real(wp), intent(in) :: k
    integer, intent(in) :: it
    integer, intent(inout) :: n
    real(wp), intent(inout) :: key(:)
    integer, intent(inout) :: item(:)
    integer :: child, parent
    n = n + 1
    child = n
    do while (child > 1)
      parent = child/2
      if (key(parent) <= k) exit
      key(child) = key(parent)
      item(child) = item(parent)
      child = parent
    end do
    key(child) = k
    item(child) = it
  end subroutine heap_push

  !> Remove the entry with the smallest key from a heap of n >= 1 entries into (k, it).
  pure subroutine heap_pop(n, key, item, k, it)
    integer, intent(inout) :: n
    real(wp), intent(inout) :: key(:)
    integer, intent(inout) :: item(:)
    real(wp), intent(out) :: k
    integer, intent(out) :: it
    real(wp) :: last_key
    integer :: last_item, parent, child
    k = key(1)
    it = item(1)
    last_key = key(n)
    last_item = item(n)
    n = n - 1
    if (n == 0) return
    parent = 1
    do
      child = 2*parent
      if (child > n) exit
      if (child < n) then
        if (key(child + 1) < key(child)) child = child + 1
      end if
      if (last_key <= key(child)) exit
      key(parent) = key(child)
      item(parent) = item(child)
      parent = child
    end do
    key(parent) = last_key
    item(parent) = last_item
  end subroutine heap_pop

end module ddpy_min_heap
