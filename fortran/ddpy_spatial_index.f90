!> Uniform cell grid over a point cloud, for nearest-neighbour queries in the global search.
!>
!> Points are bucketed by a counting sort into cells of edge h; a query visits shells of
!> cells around the query point until no unvisited cell can hold anything closer than what
!> it has found. The cell edge is chosen so that there are about two cells per point, which
!> keeps the cost of a query independent of the number of points for clouds sampled on a
!> surface. Queries return the k nearest distinct *groups* (a group being e.g. the patch a
!> grid point belongs to) with the nearest point of each: with one group per point this is
!> an ordinary k-nearest-neighbour query.
module ddpy_spatial_index
  use ddpy_kinds, only: wp
  implicit none
  private
  public :: index_layout, index_build, index_nearest_groups, offer

contains

  !> Origin, cell edge and cell counts of the grid for n points (about 2 cells per point).
  pure subroutine index_layout(n, points, origin, h, dims)
    integer, intent(in) :: n
    real(wp), intent(in) :: points(3, n)
    real(wp), intent(out) :: origin(3), h
    integer, intent(out) :: dims(3)
    real(wp) :: lower(3), upper(3), extent(3), lo, hi, target_cells
    integer :: iteration
    if (n == 0) then
      origin = 0.0_wp; h = 1.0_wp; dims = 1
      return
    end if
    lower = minval(points, dim=2)
    upper = maxval(points, dim=2)
    extent = upper - lower
    target_cells = 2.0_wp*real(n, wp)
    hi = max(maxval(extent), tiny(1.0_wp))
    lo = hi/target_cells
    ! Bisection on h for cells(h) ~ target: cells(h) decreases with h.
    do iteration = 1, 60
      h = 0.5_wp*(lo + hi)
      if (cell_count(extent, h) > target_cells) then
        lo = h
      else
        hi = h
      end if
    end do
    h = hi
    ! Pad by half a cell so that points on the bounding box are strictly inside.
    origin = lower - 0.5_wp*h
    dims = int((extent + h)/h) + 1
  contains
    pure real(wp) function cell_count(extent, h)
      real(wp), intent(in) :: extent(3), h
      cell_count = product(real(int((extent + h)/h) + 1, wp))
    end function cell_count
  end subroutine index_layout

  !> Cell of a point, clamped into the grid.
  pure function cell_of(x, origin, h, dims) result(c)
    real(wp), intent(in) :: x(3), origin(3), h
    integer, intent(in) :: dims(3)
    integer :: c(3)
    c = min(max(int(floor((x - origin)/h)), 0), dims - 1)
  end function cell_of

  pure integer function linear_cell(c, dims)
    integer, intent(in) :: c(3), dims(3)
    linear_cell = 1 + c(1) + dims(1)*(c(2) + dims(2)*c(3))
  end function linear_cell

  !> Bucket the points: items of cell j are cell_items(cell_start(j) : cell_start(j+1)-1).
  pure subroutine index_build(n, points, origin, h, dims, ncell, cell_start, cell_items)
    integer, intent(in) :: n, dims(3), ncell
    real(wp), intent(in) :: points(3, n), origin(3), h
    integer, intent(out) :: cell_start(ncell + 1), cell_items(n)
    integer :: i, j, fill(ncell), cell(n)
    cell_start = 0
    do i = 1, n
      cell(i) = linear_cell(cell_of(points(:, i), origin, h, dims), dims)
      cell_start(cell(i) + 1) = cell_start(cell(i) + 1) + 1
    end do
    cell_start(1) = 1
    do j = 1, ncell
      cell_start(j + 1) = cell_start(j + 1) + cell_start(j)
    end do
    fill = cell_start(1:ncell)
    do i = 1, n
      cell_items(fill(cell(i))) = i
      fill(cell(i)) = fill(cell(i)) + 1
    end do
  end subroutine index_build

  !> The k nearest distinct groups to x, nearest first: group(i) is the group of point i.
  !> found_item(j) is the nearest point of the j-th group, found_dist(j) its distance;
  !> nfound <= k is less than k only when the cloud has fewer groups.
  pure subroutine index_nearest_groups(x, k, n, points, group, origin, h, dims, ncell, &
                                       cell_start, cell_items, found_group, found_item, &
                                       found_dist, nfound)
    real(wp), intent(in) :: x(3), origin(3), h
    integer, intent(in) :: k, n, dims(3), ncell
    real(wp), intent(in) :: points(3, n)
    integer, intent(in) :: group(n), cell_start(ncell + 1), cell_items(n)
    integer, intent(out) :: found_group(k), found_item(k), nfound
    real(wp), intent(out) :: found_dist(k)
    integer :: c0(3), c(3), shell, i, j, jj, item, lin, last_shell
    real(wp) :: d
    logical :: face
    nfound = 0
    found_group = 0; found_item = 0; found_dist = huge(1.0_wp)
    if (n == 0 .or. k < 1) return
    c0 = cell_of(x, origin, h, dims)
    last_shell = maxval(max(c0, dims - 1 - c0))
    do shell = 0, last_shell
      do j = max(c0(3) - shell, 0), min(c0(3) + shell, dims(3) - 1)
        do jj = max(c0(2) - shell, 0), min(c0(2) + shell, dims(2) - 1)
          face = abs(j - c0(3)) == shell .or. abs(jj - c0(2)) == shell
          do i = max(c0(1) - shell, 0), min(c0(1) + shell, dims(1) - 1)
            ! Only the surface of the shell's cube: the inside was visited before.
            if (.not. (face .or. abs(i - c0(1)) == shell)) cycle
            c = [i, jj, j]
            lin = linear_cell(c, dims)
            do item = cell_start(lin), cell_start(lin + 1) - 1
              d = norm2(points(:, cell_items(item)) - x)
              call offer(group(cell_items(item)), cell_items(item), d, k, found_group, &
                         found_item, found_dist, nfound)
            end do
          end do
        end do
      end do
      ! Anything in shells beyond this one is at least shell*h away.
      if (nfound == k) then
        if (found_dist(k) <= real(shell, wp)*h) exit
      end if
    end do
  end subroutine index_nearest_groups

  !> Insert (g, point, dist) into the sorted list of the nearest distinct groups.
  pure subroutine offer(g, point, dist, k, found_group, found_item, found_dist, nfound)
    integer, intent(in) :: g, point, k
    real(wp), intent(in) :: dist
    integer, intent(inout) :: found_group(k), found_item(k), nfound
    real(wp), intent(inout) :: found_dist(k)
    integer :: m, pos
    do m = 1, nfound
      if (found_group(m) == g) then
        if (dist >= found_dist(m)) return
        ! A nearer point of a listed group: take the group out, it goes in again below.
        found_group(m:nfound - 1) = found_group(m + 1:nfound)
        found_item(m:nfound - 1) = found_item(m + 1:nfound)
        found_dist(m:nfound - 1) = found_dist(m + 1:nfound)
        nfound = nfound - 1
        exit
      end if
    end do
    if (nfound == k) then
      if (dist >= found_dist(k)) return
      nfound = k - 1
    end if
    pos = nfound + 1
    do while (pos > 1)
      if (found_dist(pos - 1) <= dist) exit
      pos = pos - 1
    end do
    found_group(pos + 1:nfound + 1) = found_group(pos:nfound)
    found_item(pos + 1:nfound + 1) = found_item(pos:nfound)
    found_dist(pos + 1:nfound + 1) = found_dist(pos:nfound)
    found_group(pos) = g
    found_item(pos) = point
    found_dist(pos) = dist
    nfound = nfound + 1
  end subroutine offer

end module ddpy_spatial_index
