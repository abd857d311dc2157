!> Sparse matrix helpers of the Newton loop.
!>
!> The assembly writes the Jacobian as coordinates with duplicates (one entry per element
!> contribution, so that threads never write to the same place). The products of the Krylov
!> solver need it with the duplicates summed, once per GMRES call: on the paper's bending
!> blank 11.7 million coordinates into 5.7 million entries. Every entry gathers its own
!> contributions (rows_build lists them), in parallel; a scatter over the coordinates would
!> run on one thread.
module ddpy_sparse
  use ddpy_kinds, only: wp
  implicit none
  private
  public :: sum_duplicates, row_structure, rows_fit, rows_build

  !> The Jacobian's coordinates summed by rows (rows_build), for the
  !> products of GMRES: row i's entries are row_start(i) + 1 .. row_start(i + 1), each in
  !> column col (0-based), the sum of the coordinate values at sources(source_start(k) +
  !> 1 .. source_start(k + 1)) (0-based). n = 0: none given (no Krylov solves).
  type :: row_structure
    integer :: n = 0
    integer, allocatable :: row_start(:), col(:), sources(:), source_start(:)
  end type row_structure

contains

  !> Whether a row structure of n rows over nvalues coordinate values is in order: rows
  !> and sources from 0 to their counts, columns in 0..n-1, sources in 0..nvalues-1.
  pure logical function rows_fit(n, ncsr, nsrc, nvalues, row_start, col, sources, &
                                 source_start) result(ok)
    integer, intent(in) :: n, ncsr, nsrc, nvalues, row_start(n + 1), col(ncsr), &
                           sources(nsrc), source_start(ncsr + 1)
    ok = row_start(1) == 0 .and. row_start(n + 1) == ncsr .and. &
         all(row_start(2:) >= row_start(:n)) .and. source_start(1) == 0 .and. &
         source_start(ncsr + 1) == nsrc .and. all(source_start(2:) >= source_start(:ncsr)) &
         .and. all(col >= 0 .and. col < n) .and. all(sources >= 0 .and. sources < nvalues)
  end function rows_fit

  !> data(i) = sum of values(sources(k) + 1) over k = starts(i) + 1 .. starts(i + 1):
  !> sources lists, entry after entry, the 0-based positions of each entry's contributions.
  subroutine sum_duplicates(n_values, n_data, values, sources, starts, data)
    integer, intent(in) :: n_values, n_data
    real(wp), intent(in) :: values(n_values)
    integer, intent(in) :: sources(*), starts(n_data + 1)
    real(wp), intent(out) :: data(n_data)
    integer :: i, k
    real(wp) :: total
    !$omp parallel do schedule(static) private(k, total)
    do i = 1, n_data
      total = 0.0_wp
      do k = starts(i) + 1, starts(i + 1)
        total = total + values(sources(k) + 1)
      end do
      data(i) = total
    end do
    !$omp end parallel do
  end subroutine sum_duplicates

  !> The row structure of the n x n matrix with m coordinates at 0-based (rows, cols), as
  !> ddpy.core.linalg.row_structure makes it: entries sorted by row, then column, each
  !> gathering its coordinates in their order; symmetric: the coordinates are one triangle,
  !> each off-diagonal one standing for its mirror too (the mirrors after every coordinate).
  !> Two stable counting sorts, by column and then by row.
  subroutine rows_build(n, m, rows, cols, symmetric, rs)
    integer, intent(in) :: n, m, rows(m), cols(m)
    logical, intent(in) :: symmetric
    type(row_structure), intent(out) :: rs
    integer, allocatable :: r(:), c(:), origin(:), next(:), by_col(:), order(:)
    logical, allocatable :: new(:)
    integer :: total, i, k, e
    total = m
    if (symmetric) total = m + count(rows /= cols)
    allocate(r(total), c(total), origin(total), next(n + 1), by_col(total), order(total))
    r(1:m) = rows
    c(1:m) = cols
    origin(1:m) = [(i - 1, i = 1, m)]
    k = m
    if (symmetric) then
      do i = 1, m
        if (rows(i) == cols(i)) cycle
        k = k + 1
        r(k) = cols(i)
        c(k) = rows(i)
        origin(k) = i - 1
      end do
    end if
    call counting_sort(c, [(i, i = 1, total)], by_col)
    call counting_sort(r, by_col, order)
    ! new(k): the k-th sorted coordinate starts an entry (its row or column changes)
    allocate(new(total))
    do k = 1, total
      new(k) = k == 1
      if (k > 1) new(k) = r(order(k)) /= r(order(k - 1)) .or. c(order(k)) /= c(order(k - 1))
    end do
    e = count(new)
    rs%n = n
    allocate(rs%row_start(n + 1), rs%col(e), rs%source_start(e + 1), rs%sources(total))
    rs%row_start = 0
    e = 0
    do k = 1, total
      i = order(k)
      rs%sources(k) = origin(i)
      if (.not. new(k)) cycle
      e = e + 1
      rs%col(e) = c(i)
      rs%source_start(e) = k - 1
      rs%row_start(r(i) + 2) = rs%row_start(r(i) + 2) + 1
    end do
    rs%source_start(e + 1) = total
    do i = 2, n + 1
      rs%row_start(i) = rs%row_start(i) + rs%row_start(i - 1)
    end do

  contains

    !> sorted: the items of items (indices into key) stably sorted by key (0..n-1).
    subroutine counting_sort(key, items, sorted)
      integer, intent(in) :: key(:), items(:)
      integer, intent(out) :: sorted(:)
      integer :: j, q
      next = 0
      do j = 1, size(items)
        next(key(items(j)) + 1) = next(key(items(j)) + 1) + 1
      end do
      q = 0
      do j = 1, n  ! next(v + 1): the entries before key v
        q = q + next(j)
        next(j) = q - next(j)
      end do
      do j = 1, size(items)
        q = key(items(j)) + 1
        next(q) = next(q) + 1
        sorted(next(q)) = items(j)
      end do
    end subroutine counting_sort

  end subroutine rows_build

end module ddpy_sparse
